//! `station::config`: real project folders in temp dirs; every semantic check asserts the
//! exact `line:col` and key of its error. By topic: `examples` (the example projects load),
//! `settings` (station and node settings), `points` (points and commands), `links` (links and
//! republishing), `servers` (command age, ports, redundancy groups, TLS), `plc_programs` (ST
//! sources and PLC variables), `lines` (serial lines and devices), `lifts`, `messages` (error
//! messages with `file:line:col`, how many), `robustness` (nothing panics) and
//! `typed_problems` (what is wrong, as a value); the shared helpers in `support`.

mod support;

mod examples;
mod lifts;
mod lines;
mod links;
mod messages;
mod plc_programs;
mod points;
mod robustness;
mod servers;
mod settings;
mod typed_problems;
