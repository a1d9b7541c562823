//! A node's shared state: its point database, the server that publishes it and the path
//! to the store. The simulation thread (PLC-sourced points), the link tasks (points of
//! lower nodes) and the command handler all change points through [`NodePoints`], which
//! keeps the three in step: a change reported by the database goes to the store and, once
//! committed there, to the server (sent or only imaged, by the point's transmission). It
//! is handed to the recorder under the node's lock and forwarded by the recorder's writer
//! in the order it was handed over, so that clients and the store see changes in the
//! order the database took them, and a process killed at any instant has stored all that
//! its clients received (store, then forward: [`Recorder::event_then`]).
//!
//! A command's return information: the command handler asks for the next change of the
//! command's feedback point ([`NodePoints::expect_return`]); that change goes out with
//! cause 11 (return information caused by a remote command), and only once it is queued at
//! the server is the command told, so that its termination follows it.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, MutexGuard};

use chrono::{DateTime, Utc};

use iec60870::asdu::Asdu;
use iec60870::time::TimeZonePolicy;
use points::{
    EventCause, Point, PointChange, PointDb, PointDbError, PointId, PointKey, PointValue, Quality,
    SourceTime, StorageFilter, StorageRule,
};
use points_iec::{event_cause, from_element, received_as_event};

use super::clock::NodeClock;
use super::sink::PointSink;
use crate::store::{EventRecord, Recorder};

/// One node's points, server and recorder.
#[derive(Debug)]
pub struct NodePoints {
    name: String,
    db: Mutex<PointDb>,
    /// The protocols serving the points upward (see [`super::sink`]); shared with the
    /// forwards waiting in the recorder for their event's commit.
    sinks: Arc<std::sync::RwLock<Vec<Arc<dyn PointSink>>>>,
    zone: TimeZonePolicy,
    recorder: Recorder,
    clock: Arc<NodeClock>,
    /// Commands waiting for the next change of a point (by name) as their return
    /// information; a waiter that gave up has dropped its receiver.
    returns: Mutex<HashMap<String, Vec<tokio::sync::oneshot::Sender<()>>>>,
    /// The storage rules of the points that have one (by name; the others store every
    /// change) and what was last stored of each.
    storage_rules: HashMap<String, StorageRule>,
    stored: Mutex<StorageFilter>,
}

impl NodePoints {
    pub(crate) fn new(
        name: &str,
        db: PointDb,
        zone: TimeZonePolicy,
        recorder: Recorder,
        clock: Arc<NodeClock>,
    ) -> Arc<NodePoints> {
        let storage_rules = db
            .points()
            .filter(|point| !point.spec.storage.is_every_change())
            .map(|point| (point.spec.name.clone(), point.spec.storage))
            .collect();
        Arc::new(NodePoints {
            name: name.to_owned(),
            storage_rules,
            stored: Mutex::new(StorageFilter::new()),
            db: Mutex::new(db),
            sinks: Arc::default(),
            zone,
            recorder,
            clock,
            returns: Mutex::new(HashMap::new()),
        })
    }

    /// Resolves once the point's next change has been published as return information
    /// (cause 11). Ask before the command is carried out, so that a fast change is not
    /// missed; drop the receiver to stop waiting.
    pub(crate) fn expect_return(&self, point: &str) -> tokio::sync::oneshot::Receiver<()> {
        let (sender, receiver) = tokio::sync::oneshot::channel();
        self.returns
            .lock()
            .unwrap_or_else(|poison| poison.into_inner())
            .entry(point.to_owned())
            .or_default()
            .push(sender);
        receiver
    }

    /// The commands waiting for this point's change as their return information (those
    /// that still wait).
    fn take_return_waiters(&self, point: &str) -> Vec<tokio::sync::oneshot::Sender<()>> {
        let mut returns = self
            .returns
            .lock()
            .unwrap_or_else(|poison| poison.into_inner());
        let waiters = returns.remove(point).unwrap_or_default();
        waiters
            .into_iter()
            .filter(|waiter| !waiter.is_closed())
            .collect()
    }

    /// Whether the store keeps this change: always, but for points with a storage rule
    /// (a deadband, a rate limit), whose changes it leaves out are only sent.
    fn to_store(&self, change: &PointChange) -> bool {
        let Some(rule) = self.storage_rules.get(&change.name) else {
            return true;
        };
        self.stored
            .lock()
            .unwrap_or_else(|poison| poison.into_inner())
            .admit(*rule, change)
    }

    /// How many changes the points' storage rules left out of the store so far.
    pub fn left_out_of_store(&self) -> u64 {
        self.stored
            .lock()
            .unwrap_or_else(|poison| poison.into_inner())
            .left_out()
    }

    /// The node's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The node's clock.
    pub fn clock(&self) -> &Arc<NodeClock> {
        &self.clock
    }

    /// The time zone of the node's time tags.
    pub fn zone(&self) -> TimeZonePolicy {
        self.zone
    }

    /// Adds a sink: from now on it gets every change of the node's points, in order.
    pub fn attach_sink(&self, sink: Arc<dyn PointSink>) {
        self.sinks
            .write()
            .unwrap_or_else(|poison| poison.into_inner())
            .push(sink);
    }

    pub(crate) fn recorder(&self) -> &Recorder {
        &self.recorder
    }

    /// Locks the database (a poisoned lock is taken over: the database has no invariant a
    /// panicking reader could break halfway).
    pub(crate) fn lock(&self) -> MutexGuard<'_, PointDb> {
        self.db.lock().unwrap_or_else(|poison| poison.into_inner())
    }

    /// A copy of one point's state.
    pub fn point<'a>(&self, key: impl Into<PointKey<'a>>) -> Option<Point> {
        self.lock().get(key).cloned()
    }

    /// A copy of every point's state, in declaration order.
    pub fn points(&self) -> Vec<Point> {
        self.lock().points().cloned().collect()
    }

    /// Updates a point and publishes the change, if any. `origin` is recorded with the
    /// event (the node itself, or the link the value came over). An `event` (a value the
    /// source sent spontaneously) is published even when unchanged.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn update<'a>(
        &self,
        key: impl Into<PointKey<'a>>,
        value: PointValue,
        quality: Quality,
        source_time: Option<SourceTime>,
        cause: EventCause,
        origin: &str,
        event: bool,
    ) -> Result<(), PointDbError> {
        let now = self.clock.now();
        // A value without its own time (an interrogation answer, a PLC variable) is
        // stamped when the node took it, on the node's clock: the server would otherwise
        // stamp it with the host's wall clock, not the station's.
        let source_time = source_time.or(Some(SourceTime {
            time: now,
            invalid: false,
        }));
        let mut db = self.lock();
        let change = if event {
            db.update_event(key, value, quality, source_time, now, cause)?
        } else {
            db.update(key, value, quality, source_time, now, cause)?
        };
        if let Some(change) = change {
            self.publish(&change, origin);
        }
        Ok(())
    }

    /// Applies the monitor data of an ASDU received from a lower station (a node below
    /// over an IEC 104 link, an IEC 101 outstation on a line) to the points each object
    /// feeds (`points_of(IOA)`), each value converted to its point's type. Confirmations,
    /// negative and test ASDUs carry no process value and are left alone.
    ///
    /// For the node above, a change is a change (report by exception): an interrogated,
    /// periodic or read value is applied as a spontaneous one, and this node's own
    /// transmission setting decides how it is sent; a spontaneous change or return
    /// information is passed on even when equal to the last value.
    pub(crate) fn apply_received<'p>(
        &self,
        origin: &str,
        asdu: &Asdu,
        points_of: impl Fn(u32) -> Option<&'p [PointId]>,
    ) {
        if asdu.cot.negative || asdu.cot.test || !asdu.type_id.is_monitor() {
            return;
        }
        let Some(received) = event_cause(asdu.cot.cause) else {
            return;
        };
        let event = received_as_event(asdu.cot.cause);
        let cause = match received {
            EventCause::Interrogated | EventCause::Cyclic => EventCause::Spontaneous,
            other => other,
        };
        for object in &asdu.objects {
            let Some(ids) = points_of(object.ioa.get()) else {
                continue;
            };
            let decoded = from_element(
                asdu.type_id,
                &object.element,
                object.time.as_ref(),
                self.zone,
            );
            let (value, quality, source_time) = match decoded {
                Ok(decoded) => decoded,
                Err(error) => {
                    tracing::warn!(node = %self.name, %origin, ioa = %object.ioa, %error, "value refused");
                    continue;
                }
            };
            for id in ids {
                if let Err(error) = self.update(
                    *id,
                    value.clone(),
                    quality,
                    source_time,
                    cause,
                    origin,
                    event,
                ) {
                    tracing::warn!(node = %self.name, %origin, %error, "value refused");
                }
            }
        }
    }

    /// Runs `f` on the locked database and publishes the changes it returns.
    pub(crate) fn change_with(
        &self,
        origin: &str,
        f: impl FnOnce(&mut PointDb, DateTime<Utc>) -> Vec<PointChange>,
    ) {
        let now = self.clock.now();
        let mut db = self.lock();
        for change in f(&mut db, now) {
            self.publish(&change, origin);
        }
    }

    /// Stores the change (unless its storage rule leaves it out) and then forwards it to
    /// the sinks and tells the commands waiting for it: store, then forward (see
    /// [`Recorder::event_then`]), so that a process killed at any instant never sent
    /// dispatch an event its store lacks.
    fn publish(&self, change: &PointChange, origin: &str) {
        let waiters = self.take_return_waiters(&change.name);
        let change = if waiters.is_empty() {
            change.clone()
        } else {
            PointChange {
                cause: EventCause::ReturnRemote,
                ..change.clone()
            }
        };
        let record = self
            .to_store(&change)
            .then(|| EventRecord::of_change(&change, &self.name, origin));
        let node = self.name.clone();
        let sinks = Arc::clone(&self.sinks);
        let forward = Box::new(move || {
            for sink in sinks
                .read()
                .unwrap_or_else(|poison| poison.into_inner())
                .iter()
            {
                if let Err(error) = sink.publish(&change) {
                    tracing::warn!(%node, point = %change.name, sink = %sink.describe(), %error, "not published");
                }
            }
            for waiter in waiters {
                let _ = waiter.send(());
            }
        });
        match record {
            Some(record) => self.recorder.event_then(record, forward),
            None => self.recorder.then(forward),
        }
    }
}
