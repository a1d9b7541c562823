//! A node's points as its IEC 104 server's process image, and each change published.

use iec60870::asdu::{Cp56Time2a, TimeTag, TimeTagKind};
use iec60870::cs104::server::{ImageError, MonitorPoint, ProcessImage, ServerError, ServerHandle};
use iec60870::time::TimeZonePolicy;
use points::{PointChange, PointDb, SourceTime};

use crate::{element, transmission_cause, type_id};

/// Why a point or a change could not be put into a server.
#[derive(Debug, thiserror::Error)]
pub enum PublishError {
    /// A point address beyond the 24 bits of an IOA (a project loader refuses them).
    #[error("point address {0} is beyond the largest information object address 16777215")]
    Address(u32),
    /// The process image refused the point.
    #[error(transparent)]
    Image(#[from] ImageError),
    /// The server refused the update.
    #[error(transparent)]
    Server(#[from] ServerError),
}

/// The CP56Time2a of a source time in `zone`, with IV from [`SourceTime::invalid`].
fn cp56(source_time: SourceTime, zone: TimeZonePolicy) -> Cp56Time2a {
    zone.to_cp56(source_time.time)
        .with_invalid(source_time.invalid)
}

/// The time tag of a change: its source time in `zone`; `None` without source time (the
/// server then stamps the time of sending).
pub fn time_tag(change: &PointChange, zone: TimeZonePolicy) -> Option<Cp56Time2a> {
    change.source_time.map(|st| cp56(st, zone))
}

/// Hands a change to the node's IEC 104 server: sent with its cause when
/// [`PointChange::send`] is set, otherwise only written to the image (interrogation and
/// read show it).
pub fn publish(
    change: &PointChange,
    server: &ServerHandle,
    zone: TimeZonePolicy,
) -> Result<(), PublishError> {
    let ioa = element::ioa(change.address).map_err(|_| PublishError::Address(change.address))?;
    let value = element::to_element(change.point_type, &change.value, change.quality);
    let time = time_tag(change, zone);
    if change.send {
        server.update_with_cause(ioa, value, time, transmission_cause(change.cause))?;
    } else {
        let time = match type_id(change.point_type).time_tag() {
            TimeTagKind::None => None,
            _ => time.map(TimeTag::Cp56),
        };
        server.set(ioa, value, time)?;
    }
    Ok(())
}

/// The IEC 104 server's process image of a point database: one monitor point per point,
/// with its type, its interrogation groups, the newest value and, for time-tagged types,
/// its source time as a CP56Time2a in `zone`.
pub fn process_image(db: &PointDb, zone: TimeZonePolicy) -> Result<ProcessImage, PublishError> {
    let mut image = ProcessImage::new();
    for point in db.points() {
        let event_type = type_id(point.spec.point_type);
        let time = match event_type.time_tag() {
            TimeTagKind::None => None,
            _ => point.source_time.map(|st| TimeTag::Cp56(cp56(st, zone))),
        };
        image.add_monitor(MonitorPoint {
            ioa: element::ioa(point.spec.address)
                .map_err(|_| PublishError::Address(point.spec.address))?,
            event_type,
            groups: point.spec.groups,
            element: element::to_element(point.spec.point_type, &point.value, point.quality),
            time,
        })?;
    }
    Ok(image)
}
