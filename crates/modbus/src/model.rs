//! A server's data: the four tables of the Modbus data model (coils, discrete inputs,
//! holding registers, input registers), for one unit or one per unit, shared by every
//! connection and line that serves them, and an event per write by a client.
//!
//! The station runtime serves a node's points from a [`DataModel`]: it writes measured
//! values and states with [`DataModel::write`] (no event: those are not a client's) and
//! learns of a client's commands from [`DataModel::subscribe`].

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;
use std::sync::{Arc, Mutex, PoisonError};

use thiserror::Error;
use tokio::sync::mpsc;

use crate::pdu::{
    ExceptionCode, FunctionCode, Request, Response, MAX_READ_BITS, MAX_READ_REGISTERS,
};

/// One of the four tables.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Table {
    /// Read-write bits (FC 1, 5, 15).
    Coils,
    /// Read-only bits (FC 2).
    DiscreteInputs,
    /// Read-write registers (FC 3, 6, 16, 23).
    HoldingRegisters,
    /// Read-only registers (FC 4).
    InputRegisters,
}

impl Table {
    /// The four, in the order of their read function codes.
    pub const ALL: [Table; 4] = [
        Table::Coils,
        Table::DiscreteInputs,
        Table::HoldingRegisters,
        Table::InputRegisters,
    ];

    /// The short name of the command line and of JSON: `coils`, `discrete`, `holding`,
    /// `input`.
    pub fn name(self) -> &'static str {
        match self {
            Table::Coils => "coils",
            Table::DiscreteInputs => "discrete",
            Table::HoldingRegisters => "holding",
            Table::InputRegisters => "input",
        }
    }

    /// The name in the specification's words: `coils`, `discrete inputs`, ...
    pub fn long_name(self) -> &'static str {
        match self {
            Table::Coils => "coils",
            Table::DiscreteInputs => "discrete inputs",
            Table::HoldingRegisters => "holding registers",
            Table::InputRegisters => "input registers",
        }
    }

    /// Whether its entries are bits (coils, discrete inputs) rather than registers.
    pub fn is_bits(self) -> bool {
        matches!(self, Table::Coils | Table::DiscreteInputs)
    }

    /// Whether a client may write it (coils, holding registers).
    pub fn is_writable(self) -> bool {
        matches!(self, Table::Coils | Table::HoldingRegisters)
    }

    /// The function code that reads it.
    pub fn read_function(self) -> FunctionCode {
        match self {
            Table::Coils => FunctionCode::READ_COILS,
            Table::DiscreteInputs => FunctionCode::READ_DISCRETE_INPUTS,
            Table::HoldingRegisters => FunctionCode::READ_HOLDING_REGISTERS,
            Table::InputRegisters => FunctionCode::READ_INPUT_REGISTERS,
        }
    }

    /// Most entries one read asks for: 2000 bits or 125 registers.
    pub fn max_read(self) -> u16 {
        if self.is_bits() {
            MAX_READ_BITS
        } else {
            MAX_READ_REGISTERS
        }
    }
}

impl fmt::Display for Table {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A table name other than the four.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("table {0:?}: expected coils, discrete, holding or input")]
pub struct TableError(pub String);

impl FromStr for Table {
    type Err = TableError;

    /// The short names and the long ones (`discrete-inputs`, `holding registers`).
    fn from_str(text: &str) -> Result<Table, TableError> {
        let lower = text.trim().to_ascii_lowercase().replace(['-', '_'], " ");
        match lower.as_str() {
            "coils" | "coil" => Ok(Table::Coils),
            "discrete" | "discrete inputs" => Ok(Table::DiscreteInputs),
            "holding" | "holding registers" => Ok(Table::HoldingRegisters),
            "input" | "input registers" => Ok(Table::InputRegisters),
            _ => Err(TableError(text.to_owned())),
        }
    }
}

/// Entries of a table: bits or registers.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Values {
    /// Coils or discrete inputs.
    Bits(Vec<bool>),
    /// Holding or input registers.
    Registers(Vec<u16>),
}

impl Values {
    /// How many entries.
    pub fn len(&self) -> usize {
        match self {
            Values::Bits(bits) => bits.len(),
            Values::Registers(registers) => registers.len(),
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Which unit ids a data model answers, and with which tables.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum Units {
    /// One set of tables answering every unit id (a TCP device that ignores the unit
    /// id; a serial slave that answers every address but the broadcast 0).
    #[default]
    Any,
    /// One set of tables answering one unit id only.
    Single(u8),
    /// A set of tables for each unit id listed (a gateway's line, a rack of devices).
    PerUnit(Vec<u8>),
}

/// How a [`DataModel`] is made.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct ModelConfig {
    /// The unit ids served.
    pub units: Units,
    /// Entries in each table, addresses `0..size` (10,000 by default; at most 65,536).
    pub size: usize,
}

impl Default for ModelConfig {
    fn default() -> Self {
        ModelConfig {
            units: Units::Any,
            size: DataModel::DEFAULT_SIZE,
        }
    }
}

impl ModelConfig {
    /// One set of tables of the default size for `units`.
    pub fn new(units: Units) -> ModelConfig {
        ModelConfig {
            units,
            ..ModelConfig::default()
        }
    }
}

/// A write by a client: which unit, table and entries, and the values written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WriteEvent {
    /// The unit id the request addressed (0: a serial line's broadcast).
    pub unit: u8,
    /// Coils or holding registers.
    pub table: Table,
    /// The first entry written.
    pub address: u16,
    /// The values from there on.
    pub values: Values,
}

impl WriteEvent {
    /// How many entries were written.
    pub fn count(&self) -> usize {
        self.values.len()
    }
}

/// An access to a data model that it cannot do.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum AccessError {
    /// The model does not serve the unit id.
    #[error("unit {0} is not served")]
    UnknownUnit(u8),
    /// Entries outside the table.
    #[error("{table} {address}+{count} outside 0..{size}")]
    OutOfRange {
        /// The table.
        table: Table,
        /// The first entry.
        address: u16,
        /// How many.
        count: usize,
        /// The table's size.
        size: usize,
    },
    /// Bits for a register table or registers for a bit table.
    #[error("{table} hold {}, not the values given", if table.is_bits() { "bits" } else { "registers" })]
    WrongKind {
        /// The table.
        table: Table,
    },
}

/// The four tables of one unit.
#[derive(Debug, Clone)]
struct Tables {
    coils: Vec<bool>,
    discrete: Vec<bool>,
    holding: Vec<u16>,
    input: Vec<u16>,
}

impl Tables {
    fn new(size: usize) -> Tables {
        Tables {
            coils: vec![false; size],
            discrete: vec![false; size],
            holding: vec![0; size],
            input: vec![0; size],
        }
    }

    fn range(
        &self,
        table: Table,
        address: u16,
        count: usize,
    ) -> Result<std::ops::Range<usize>, AccessError> {
        let size = self.coils.len();
        let start = usize::from(address);
        let end = start.saturating_add(count);
        if count == 0 || end > size {
            return Err(AccessError::OutOfRange {
                table,
                address,
                count,
                size,
            });
        }
        Ok(start..end)
    }

    fn read(&self, table: Table, address: u16, count: usize) -> Result<Values, AccessError> {
        let range = self.range(table, address, count)?;
        let out_of_range = || AccessError::OutOfRange {
            table,
            address,
            count,
            size: self.coils.len(),
        };
        Ok(match table {
            Table::Coils => Values::Bits(self.coils.get(range).ok_or_else(out_of_range)?.to_vec()),
            Table::DiscreteInputs => {
                Values::Bits(self.discrete.get(range).ok_or_else(out_of_range)?.to_vec())
            }
            Table::HoldingRegisters => {
                Values::Registers(self.holding.get(range).ok_or_else(out_of_range)?.to_vec())
            }
            Table::InputRegisters => {
                Values::Registers(self.input.get(range).ok_or_else(out_of_range)?.to_vec())
            }
        })
    }

    fn write(&mut self, table: Table, address: u16, values: &Values) -> Result<(), AccessError> {
        let range = self.range(table, address, values.len())?;
        let size = self.coils.len();
        let out_of_range = || AccessError::OutOfRange {
            table,
            address,
            count: values.len(),
            size,
        };
        match (table, values) {
            (Table::Coils, Values::Bits(bits)) => self
                .coils
                .get_mut(range)
                .ok_or_else(out_of_range)?
                .copy_from_slice(bits),
            (Table::DiscreteInputs, Values::Bits(bits)) => self
                .discrete
                .get_mut(range)
                .ok_or_else(out_of_range)?
                .copy_from_slice(bits),
            (Table::HoldingRegisters, Values::Registers(registers)) => self
                .holding
                .get_mut(range)
                .ok_or_else(out_of_range)?
                .copy_from_slice(registers),
            (Table::InputRegisters, Values::Registers(registers)) => self
                .input
                .get_mut(range)
                .ok_or_else(out_of_range)?
                .copy_from_slice(registers),
            _ => return Err(AccessError::WrongKind { table }),
        }
        Ok(())
    }
}

#[derive(Debug)]
enum Storage {
    One(Tables),
    PerUnit(BTreeMap<u8, Tables>),
}

#[derive(Debug)]
struct Inner {
    units: Units,
    size: usize,
    storage: Mutex<Storage>,
    subscribers: Mutex<Vec<mpsc::UnboundedSender<WriteEvent>>>,
}

/// The tables a server serves, shared: clones are handles to the same tables, so every
/// connection of a TCP server, a serial slave and the station runtime see one state.
///
/// Each call locks the tables for its duration: a request is carried out whole before
/// another is (FC 23's write and read included).
#[derive(Debug, Clone)]
pub struct DataModel {
    inner: Arc<Inner>,
}

impl Default for DataModel {
    /// One set of 10,000-entry tables answering every unit id.
    fn default() -> Self {
        DataModel::new(ModelConfig::default())
    }
}

impl DataModel {
    /// Entries in each table unless configured otherwise.
    pub const DEFAULT_SIZE: usize = 10_000;

    /// Zeroed tables as configured (a size above 65,536 is taken as 65,536).
    pub fn new(config: ModelConfig) -> DataModel {
        let size = config.size.min(usize::from(u16::MAX) + 1);
        let storage = match &config.units {
            Units::Any | Units::Single(_) => Storage::One(Tables::new(size)),
            Units::PerUnit(units) => Storage::PerUnit(
                units
                    .iter()
                    .map(|unit| (*unit, Tables::new(size)))
                    .collect(),
            ),
        };
        DataModel {
            inner: Arc::new(Inner {
                units: config.units,
                size,
                storage: Mutex::new(storage),
                subscribers: Mutex::new(Vec::new()),
            }),
        }
    }

    /// The unit ids served.
    pub fn units(&self) -> &Units {
        &self.inner.units
    }

    /// Entries in each table.
    pub fn size(&self) -> usize {
        self.inner.size
    }

    /// Whether requests for `unit` are this model's.
    pub fn serves(&self, unit: u8) -> bool {
        match &self.inner.units {
            Units::Any => true,
            Units::Single(only) => *only == unit,
            Units::PerUnit(units) => units.contains(&unit),
        }
    }

    /// Reads `count` entries from `address`, as a client would without the limits of one
    /// request.
    pub fn read(
        &self,
        unit: u8,
        table: Table,
        address: u16,
        count: usize,
    ) -> Result<Values, AccessError> {
        self.with_tables(unit, |tables| tables.read(table, address, count))
    }

    /// Writes entries of any table from the server's side (the station runtime's
    /// measurements and states): no [`WriteEvent`].
    pub fn write(
        &self,
        unit: u8,
        table: Table,
        address: u16,
        values: &Values,
    ) -> Result<(), AccessError> {
        self.with_tables(unit, |tables| tables.write(table, address, values))
    }

    /// A receiver of every [`WriteEvent`] from now on (until it is dropped).
    pub fn subscribe(&self) -> mpsc::UnboundedReceiver<WriteEvent> {
        let (sender, receiver) = mpsc::unbounded_channel();
        self.inner
            .subscribers
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(sender);
        receiver
    }

    /// Carries out a client's request for `unit`: the response, or the exception to
    /// answer (2 for entries outside the tables, 0x0B for a unit not served). Writes are
    /// announced to the subscribers.
    ///
    /// The request's quantities are checked as [`Request::decode`] does (exception 3), so
    /// a request made in code is held to the same limits as one from a line.
    pub fn execute(&self, unit: u8, request: &Request) -> Result<Response, ExceptionCode> {
        if !self.serves(unit) {
            return Err(ExceptionCode::GATEWAY_TARGET_FAILED);
        }
        request
            .validate()
            .map_err(|_| ExceptionCode::ILLEGAL_DATA_VALUE)?;
        let mut events = Vec::new();
        let response = self
            .with_tables(unit, |tables| {
                Self::apply(tables, unit, request, &mut events)
            })
            .map_err(|_| ExceptionCode::ILLEGAL_DATA_ADDRESS)?;
        self.announce(events);
        Ok(response)
    }

    /// Carries out a broadcast write (unit 0 on a serial line) on every unit's tables;
    /// reads are not broadcast and are ignored. Nothing is answered.
    pub fn execute_broadcast(&self, request: &Request) {
        if matches!(
            request,
            Request::Read { .. } | Request::ReadWriteMultipleRegisters { .. }
        ) || request.validate().is_err()
        {
            return;
        }
        let mut events = Vec::new();
        {
            let mut storage = self.lock();
            let all: Vec<&mut Tables> = match &mut *storage {
                Storage::One(tables) => vec![tables],
                Storage::PerUnit(map) => map.values_mut().collect(),
            };
            let mut first = true;
            for tables in all {
                let mut unit_events = Vec::new();
                if Self::apply(tables, 0, request, &mut unit_events).is_ok() && first {
                    events = unit_events;
                    first = false;
                }
            }
        }
        self.announce(events);
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Storage> {
        self.inner
            .storage
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
    }

    fn with_tables<T>(
        &self,
        unit: u8,
        f: impl FnOnce(&mut Tables) -> Result<T, AccessError>,
    ) -> Result<T, AccessError> {
        if !self.serves(unit) {
            return Err(AccessError::UnknownUnit(unit));
        }
        let mut storage = self.lock();
        let tables = match &mut *storage {
            Storage::One(tables) => Some(tables),
            Storage::PerUnit(map) => map.get_mut(&unit),
        };
        f(tables.ok_or(AccessError::UnknownUnit(unit))?)
    }

    /// One request on one unit's tables; a write's event is added to `events`. Nothing
    /// is changed when the request fails (FC 23's write is checked with its read first).
    fn apply(
        tables: &mut Tables,
        unit: u8,
        request: &Request,
        events: &mut Vec<WriteEvent>,
    ) -> Result<Response, AccessError> {
        let mut written = |table: Table, address: u16, values: Values| {
            events.push(WriteEvent {
                unit,
                table,
                address,
                values,
            });
        };
        Ok(match request {
            Request::Read {
                table,
                address,
                count,
            } => match tables.read(*table, *address, usize::from(*count))? {
                Values::Bits(bits) if *table == Table::Coils => Response::ReadCoils(bits),
                Values::Bits(bits) => Response::ReadDiscreteInputs(bits),
                Values::Registers(registers) if *table == Table::HoldingRegisters => {
                    Response::ReadHoldingRegisters(registers)
                }
                Values::Registers(registers) => Response::ReadInputRegisters(registers),
            },
            Request::WriteSingleCoil { address, value } => {
                let values = Values::Bits(vec![*value]);
                tables.write(Table::Coils, *address, &values)?;
                written(Table::Coils, *address, values);
                Response::WriteSingleCoil {
                    address: *address,
                    value: *value,
                }
            }
            Request::WriteSingleRegister { address, value } => {
                let values = Values::Registers(vec![*value]);
                tables.write(Table::HoldingRegisters, *address, &values)?;
                written(Table::HoldingRegisters, *address, values);
                Response::WriteSingleRegister {
                    address: *address,
                    value: *value,
                }
            }
            Request::WriteMultipleCoils { address, values } => {
                let values = Values::Bits(values.clone());
                let count = u16::try_from(values.len()).unwrap_or(u16::MAX);
                tables.write(Table::Coils, *address, &values)?;
                written(Table::Coils, *address, values);
                Response::WriteMultipleCoils {
                    address: *address,
                    count,
                }
            }
            Request::WriteMultipleRegisters { address, values } => {
                let values = Values::Registers(values.clone());
                let count = u16::try_from(values.len()).unwrap_or(u16::MAX);
                tables.write(Table::HoldingRegisters, *address, &values)?;
                written(Table::HoldingRegisters, *address, values);
                Response::WriteMultipleRegisters {
                    address: *address,
                    count,
                }
            }
            Request::ReadWriteMultipleRegisters {
                read_address,
                read_count,
                write_address,
                values,
            } => {
                // Both ranges are checked before anything is written.
                tables.range(
                    Table::HoldingRegisters,
                    *read_address,
                    usize::from(*read_count),
                )?;
                let values = Values::Registers(values.clone());
                tables.write(Table::HoldingRegisters, *write_address, &values)?;
                written(Table::HoldingRegisters, *write_address, values);
                match tables.read(
                    Table::HoldingRegisters,
                    *read_address,
                    usize::from(*read_count),
                )? {
                    Values::Registers(registers) => Response::ReadWriteMultipleRegisters(registers),
                    Values::Bits(_) => {
                        return Err(AccessError::WrongKind {
                            table: Table::HoldingRegisters,
                        })
                    }
                }
            }
        })
    }

    fn announce(&self, events: Vec<WriteEvent>) {
        if events.is_empty() {
            return;
        }
        let mut subscribers = self
            .inner
            .subscribers
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        subscribers.retain(|subscriber| {
            events
                .iter()
                .all(|event| subscriber.send(event.clone()).is_ok())
        });
    }
}
