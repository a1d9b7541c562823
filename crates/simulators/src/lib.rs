//! Simulated field devices, beside the plants (`plant::registry`): what a project or the
//! CLI can simulate by name instead of a real device on a line.
//!
//! | module       | what it holds                                                         |
//! |--------------|-----------------------------------------------------------------------|
//! | [`ref630`]   | the ABB REF630 feeder protection relay of the gateway thesis, its IEC 103 side sans-IO: measurands with waveforms, indications, commands with LOCAL/REMOTE, earth faults with disturbance records, and the relay tester's console |
//! | [`registry`] | the simulated devices by name (`simulate = "ref630"`, `simulate = "ekm66"`): the protocol each speaks, what it is, its console's help |
//!
//! The EKM66 lift board's simulator lives with its driver in `devices::ekm66::simulator`
//! (one crate for the board's protocol, both ends); the registry names it all the same, so
//! the project loader, the runtime's console and the CLI find every simulated device in
//! one place. A teaching lab's model on a line is one more row.
//!
//! The protocol crate `iec60870` holds no simulator: the relay speaks IEC 103 through its
//! `ft12::SecondaryApplication` like any application would.

pub mod ref630;
pub mod registry;
