//! The poller and the simulator over a real pseudo-terminal pair with the tokio drive
//! loops: status changes, trips, counters, faults, a restart of the monitor and of the
//! board across the wrap-around of the fault index, and a board that goes silent.
//! Every wait is bounded and waits for a condition.

use std::ops::ControlFlow;
use std::time::Duration;

use devices::ekm66::codec::{FaultRecord, Status};
use devices::ekm66::io::{run_poller, run_simulator, EndpointAction, Transport};
use devices::ekm66::poller::*;
use devices::ekm66::simulator::*;
use serial_line::{LineSettings, Parity};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;

fn now() -> std::time::Instant {
    tokio::time::Instant::now().into_std()
}

type SimActions = mpsc::UnboundedSender<EndpointAction<Simulator>>;

/// The simulator on a new pseudo-terminal: its actions, the path for the poller, the
/// faults it stores and its task.
async fn start_simulator(
    config: SimulatorConfig,
) -> (
    SimActions,
    String,
    mpsc::UnboundedReceiver<SimEvent>,
    JoinHandle<()>,
) {
    let line = Transport::Pty.open().await.unwrap();
    let path = line.pty_path.clone().unwrap();
    let (actions, mut receiver) = mpsc::unbounded_channel();
    let (events, event_receiver) = mpsc::unbounded_channel();
    let task = tokio::spawn(async move {
        // The whole line moves in (not only its stream): it holds the pseudo-terminal's
        // other end open.
        let line = line;
        let mut simulator = Simulator::new(config, now());
        let result = run_simulator(line.stream, &mut simulator, &mut receiver, |event| {
            let _ = events.send(event);
            ControlFlow::Continue(())
        })
        .await;
        panic!("the simulator stopped: {result:?}");
    });
    (actions, path, event_receiver, task)
}

/// The poller on the pseudo-terminal's other end, from a stored cursor.
fn start_poller(
    path: &str,
    cursor: ArchiveCursor,
) -> (
    mpsc::UnboundedReceiver<(Event, ArchiveCursor)>,
    JoinHandle<()>,
) {
    let path = path.to_owned();
    let (sender, receiver) = mpsc::unbounded_channel();
    let task = tokio::spawn(async move {
        // A pseudo-terminal keeps no parity: 8N1, or the port refuses the board's 8E1.
        let line = Transport::Serial {
            path,
            line: LineSettings {
                parity: Parity::None,
                ..LineSettings::new(9600)
            },
        }
        .open()
        .await
        .unwrap();
        let mut config = PollerConfig::default();
        config.poll_period = Duration::from_millis(100);
        config.counters_period = Duration::from_secs(1);
        config.reply_timeout = Duration::from_millis(300);
        let mut poller = Poller::new(config, cursor, now());
        let (_actions, mut receiver) = mpsc::unbounded_channel();
        let _ = run_poller(line.stream, &mut poller, &mut receiver, |event, cursor| {
            let _ = sender.send((event, cursor.clone()));
            ControlFlow::Continue(())
        })
        .await;
    });
    (receiver, task)
}

/// What the monitor keeps: the archive and the stored cursor.
#[derive(Default)]
struct Monitor {
    archive: Vec<FaultRecord>,
    cursor: ArchiveCursor,
    statuses: Vec<Status>,
    counters: Vec<Vec<u32>>,
    comm: Vec<CommStatus>,
}

impl Monitor {
    /// Takes events until `done` holds; fails after 20 s.
    async fn until(
        &mut self,
        events: &mut mpsc::UnboundedReceiver<(Event, ArchiveCursor)>,
        what: &str,
        mut done: impl FnMut(&Monitor) -> bool,
    ) {
        let deadline = tokio::time::Instant::now() + Duration::from_secs(20);
        while !done(self) {
            let next = tokio::time::timeout_at(deadline, events.recv())
                .await
                .unwrap_or_else(|_| panic!("timed out waiting for {what}"))
                .expect("the poller stopped");
            match next {
                (Event::Fault(record), cursor) => {
                    self.archive.push(record);
                    self.cursor = cursor;
                }
                (Event::Status(status), _) => self.statuses.push(status),
                (Event::Counters(counters), _) => self.counters.push(counters),
                (Event::Comm(status), _) => self.comm.push(status),
                _ => {}
            }
        }
    }
}

fn history(events: &mut mpsc::UnboundedReceiver<SimEvent>, into: &mut Vec<FaultRecord>) {
    while let Ok(event) = events.try_recv() {
        if let SimEvent::FaultStored(record) = event {
            into.push(record);
        }
    }
}

fn act(actions: &SimActions, action: impl FnOnce(&mut Simulator) + Send + 'static) {
    actions.send(Box::new(action)).unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn poller_and_simulator_over_a_pseudo_terminal() {
    let mut config = SimulatorConfig::default();
    config.speed = 20.0;
    config.stack_size = 4;
    config.fault_probability = 0.0;
    config.status_probability = 0.0;
    config.seed = 21;
    let (actions, path, mut sim_events, _sim) = start_simulator(config.clone()).await;
    let mut board_history = Vec::new();
    let mut monitor = Monitor::default();
    let (mut events, poller) = start_poller(&path, ArchiveCursor::default());

    // Trips (several floors, the car moving), counters, a held status and its release.
    monitor
        .until(&mut events, "trips", |m| {
            let floors: std::collections::BTreeSet<u8> =
                m.statuses.iter().map(|s| s.position).collect();
            floors.len() >= 3 && m.counters.len() >= 2
        })
        .await;
    assert_eq!(monitor.comm, vec![CommStatus::Ok]);
    assert!(monitor.counters.last().unwrap().iter().sum::<u32>() > 0);
    act(&actions, |sim| sim.hold_status(18));
    monitor
        .until(&mut events, "status 18", |m| {
            m.statuses.last().unwrap().code == 18
        })
        .await;
    act(&actions, |sim| sim.release_status());
    monitor
        .until(&mut events, "status 1", |m| {
            m.statuses.last().unwrap().code == 1
        })
        .await;

    // Faults.
    act(&actions, |sim| {
        for code in [0x3C, 0x11, 0x45] {
            sim.inject_fault(code);
        }
    });
    monitor
        .until(&mut events, "3 faults", |m| m.archive.len() == 3)
        .await;

    // The monitor restarts while two faults wrap the index (stack of 4).
    poller.abort();
    let _ = poller.await;
    act(&actions, |sim| {
        sim.inject_fault(0x2B);
        sim.inject_fault(0x5E);
    });
    let (mut events, poller) = start_poller(&path, monitor.cursor.clone());
    monitor
        .until(&mut events, "5 faults", |m| m.archive.len() == 5)
        .await;
    history(&mut sim_events, &mut board_history);
    let essence = |records: &[FaultRecord]| -> Vec<(u8, u8, u8)> {
        records.iter().map(|r| (r.index, r.code, r.floor)).collect()
    };
    assert_eq!(essence(&monitor.archive), essence(&board_history));
    assert_eq!(
        monitor.archive.last().unwrap().index,
        0,
        "the index wrapped"
    );

    // The board restarts (silent while it boots, then a new instance with its
    // non-volatile memory) and stores two more faults.
    let restart = config.clone();
    act(&actions, |sim| sim.set_silent(true));
    monitor
        .until(&mut events, "communication lost", |m| {
            m.comm.last() == Some(&CommStatus::Lost)
        })
        .await;
    act(&actions, move |sim| {
        *sim = Simulator::with_memory(restart, sim.memory().clone(), now());
        sim.inject_fault(0x01);
        sim.inject_fault(0x30);
    });
    monitor
        .until(&mut events, "communication back", |m| {
            m.comm.last() == Some(&CommStatus::Ok)
        })
        .await;
    monitor
        .until(&mut events, "7 faults", |m| m.archive.len() == 7)
        .await;
    // The restarted board's faults reach the test through its new instance's events;
    // build the expected history from the archive's last two plus the board's memory.
    history(&mut sim_events, &mut board_history);
    assert_eq!(essence(&monitor.archive[..5]), essence(&board_history[..5]));
    let codes: Vec<u8> = monitor.archive.iter().map(|r| r.code).collect();
    assert_eq!(codes, vec![0x3C, 0x11, 0x45, 0x2B, 0x5E, 0x01, 0x30]);
    let keys: std::collections::BTreeSet<FaultKey> =
        monitor.archive.iter().map(FaultKey::from).collect();
    assert_eq!(keys.len(), 7, "no duplicate");
    // Indices follow the ring of four: 0 1 2 3 0 1 2.
    let indices: Vec<u8> = monitor.archive.iter().map(|r| r.index).collect();
    assert_eq!(indices, vec![0, 1, 2, 3, 0, 1, 2]);
    poller.abort();
}
