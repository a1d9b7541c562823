//! `--simulate`: values that change over time, sent spontaneously.
//!
//! Each tick changes a few random points: single and double points toggle, step
//! positions move by one, bit strings flip a bit, measurements walk by a few percent of
//! their range, counters count up.

use std::time::Duration;

use iec60870::asdu::{BinaryCounterReading, DoublePointState, Element, StepPosition};
use std::sync::Arc;

use iec60870::outstation::Outstation;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use super::points_file::PointRow;

pub(crate) async fn run(server: Arc<Outstation>, points: Vec<PointRow>, interval: Duration) {
    if points.is_empty() {
        return;
    }
    let mut random = StdRng::seed_from_u64(0x0053_5441_4E49_4345);
    let mut ticker = tokio::time::interval(interval);
    ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        ticker.tick().await;
        let changes = random.random_range(1..=3usize).min(points.len());
        for _ in 0..changes {
            let index = random.random_range(0..points.len());
            let Some(row) = points.get(index) else {
                continue;
            };
            let Some(current) = server.get(row.ioa) else {
                continue;
            };
            let next = change(&current.element, &mut random);
            if let Err(error) = server.update(row.ioa, next, None) {
                tracing::warn!(%error, ioa = %row.ioa, "simulation update refused");
            }
        }
    }
}

fn change(element: &Element, random: &mut StdRng) -> Element {
    match element.clone() {
        Element::SinglePoint { on, quality } => Element::SinglePoint { on: !on, quality },
        Element::DoublePoint { state, quality } => Element::DoublePoint {
            state: if state == DoublePointState::On {
                DoublePointState::Off
            } else {
                DoublePointState::On
            },
            quality,
        },
        Element::StepPosition { position, quality } => {
            let value =
                (position.value() + if random.random_bool(0.5) { 1 } else { -1 }).clamp(-64, 63);
            Element::StepPosition {
                position: StepPosition::new(value, false).unwrap_or(position),
                quality,
            }
        }
        Element::Bitstring { bits, quality } => Element::Bitstring {
            bits: bits ^ (1 << random.random_range(0..32u32)),
            quality,
        },
        Element::Normalized { raw, quality } => Element::Normalized {
            raw: raw.saturating_add(random.random_range(-655..=655i16)),
            quality,
        },
        Element::Scaled { value, quality } => Element::Scaled {
            value: value.saturating_add(random.random_range(-50..=50i16)),
            quality,
        },
        Element::Float { value, quality } => {
            let step = (value.abs().max(1.0)) * random.random_range(-0.02..=0.02f32);
            Element::Float {
                value: value + step,
                quality,
            }
        }
        Element::IntegratedTotal(reading) => {
            let value = reading.value().wrapping_add(random.random_range(1..=10i32));
            Element::IntegratedTotal(
                BinaryCounterReading::new(value, reading.sequence().wrapping_add(1) & 0x1F)
                    .unwrap_or(reading),
            )
        }
        other => other,
    }
}
