//! The unbalanced secondary station (the slave on a polled line), sans-IO.

use super::frame::{AddressSize, Control, Frame, PrimaryFunction, SecondaryFunction};

/// What the application above a secondary link does: the IEC 101 outstation or the
/// IEC 103 protection device.
pub trait SecondaryApplication {
    /// The primary reset the link: [`PrimaryFunction::ResetRemoteLink`] (103: reset of
    /// the communication unit, answered later with identification COT 4) or
    /// [`PrimaryFunction::ResetFcb`] (103: COT 3).
    fn link_reset(&mut self, function: PrimaryFunction);

    /// User data from the primary; `broadcast` for send/no reply. Returns `false` when
    /// the application cannot take it now (answered NACK busy; the primary repeats).
    fn user_data(&mut self, asdu: &[u8], broadcast: bool) -> bool;

    /// Whether class 1 data is waiting (ACD).
    fn has_class1(&self) -> bool;

    /// The next class 1 ASDU.
    fn class1(&mut self) -> Option<Vec<u8>>;

    /// The next class 2 ASDU.
    fn class2(&mut self) -> Option<Vec<u8>>;

    /// Whether a further user data frame could overflow the application (DFC).
    fn data_flow_stopped(&self) -> bool {
        false
    }
}

/// Settings of a secondary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SecondaryConfig {
    /// The link address field size of the line.
    pub address_size: AddressSize,
    /// This station's link address.
    pub address: u16,
    /// Answer "ACK" and "no data" with the single character E5 where it may (only when
    /// no class 1 data is waiting, since E5 carries no ACD). Off by default, as the
    /// REF630 answers with fixed frames.
    pub single_character: bool,
    /// Class 1 data before class 2 when class 2 is requested and class 1 is waiting
    /// (IEC 101 7.2.2); a 103 device answers only what is asked.
    pub class1_on_class2_request: bool,
}

impl SecondaryConfig {
    /// A secondary at `address` with a one-octet address field and fixed-frame answers.
    pub fn new(address: u16) -> SecondaryConfig {
        SecondaryConfig {
            address_size: AddressSize::One,
            address,
            single_character: false,
            class1_on_class2_request: false,
        }
    }
}

/// Counters of what the secondary saw.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SecondaryStats {
    /// Frames addressed to this station (broadcasts included).
    pub requests: u64,
    /// Repeats answered from the last response, without the application.
    pub repeats: u64,
    /// Broadcasts received.
    pub broadcasts: u64,
    /// Requests refused before the link was reset.
    pub before_reset: u64,
}

/// One secondary station's link layer: answers the primary's frames.
///
/// A repeat (FCV = 1 with the same FCB as the last accepted frame) is answered with the
/// last response again and does not reach the application: the primary repeats when
/// our answer was lost, and the user data or class data it carried must not be taken or
/// given twice. Until the primary resets the link (function 0), functions with FCV are
/// refused (NACK: link service not functioning), as a reset of remote link must start
/// every link.
#[derive(Debug, Clone)]
pub struct Secondary {
    config: SecondaryConfig,
    reset: bool,
    /// The FCB of the last accepted frame with FCV = 1; `None` right after a reset, so the
    /// next frame is new whatever its FCB.
    last_fcb: Option<bool>,
    last_response: Option<Frame>,
    stats: SecondaryStats,
}

impl Secondary {
    /// A secondary that has not been reset yet.
    pub fn new(config: SecondaryConfig) -> Secondary {
        Secondary {
            config,
            reset: false,
            last_fcb: None,
            last_response: None,
            stats: SecondaryStats::default(),
        }
    }

    /// The settings.
    pub fn config(&self) -> &SecondaryConfig {
        &self.config
    }

    /// What it has seen.
    pub fn stats(&self) -> SecondaryStats {
        self.stats
    }

    /// Whether the primary has reset the link.
    pub fn is_reset(&self) -> bool {
        self.reset
    }

    /// Handles one frame from the line and returns the answer to transmit, if any.
    ///
    /// Frames for other stations, secondary frames (another slave's answers) and
    /// broadcasts get no answer.
    pub fn handle(&mut self, frame: &Frame, app: &mut dyn SecondaryApplication) -> Option<Frame> {
        let (control, address, asdu) = match frame {
            Frame::Fixed { control, address } => (*control, *address, None),
            Frame::Variable {
                control,
                address,
                asdu,
            } => (*control, *address, Some(asdu.as_slice())),
            Frame::SingleCharacter => return None,
        };
        if !control.is_primary() {
            return None;
        }
        let broadcast = self.config.address_size.broadcast() == Some(address);
        if address != self.config.address && !broadcast {
            return None;
        }
        self.stats.requests += 1;
        let function = control.primary_function();
        if broadcast {
            // Send/no reply only: a broadcast must not make every station answer at once.
            self.stats.broadcasts += 1;
            if let (PrimaryFunction::UserDataNoReply, Some(asdu)) = (function, asdu) {
                app.user_data(asdu, true);
            }
            return None;
        }
        if control.fcv() && function.uses_fcb() {
            if !self.reset {
                self.stats.before_reset += 1;
                return Some(self.fixed(SecondaryFunction::NotFunctioning, app));
            }
            if self.last_fcb == Some(control.fcb()) {
                if let Some(last) = &self.last_response {
                    self.stats.repeats += 1;
                    return Some(last.clone());
                }
            }
        }
        let response = match function {
            PrimaryFunction::ResetRemoteLink | PrimaryFunction::ResetFcb => {
                self.reset = true;
                app.link_reset(function);
                self.last_fcb = None;
                self.last_response = None;
                return Some(self.ack(app));
            }
            PrimaryFunction::RequestLinkStatus => {
                return Some(self.fixed(SecondaryFunction::LinkStatus, app));
            }
            PrimaryFunction::ResetUserProcess => {
                return Some(self.ack(app));
            }
            PrimaryFunction::UserDataNoReply => {
                if let Some(asdu) = asdu {
                    app.user_data(asdu, false);
                }
                return None;
            }
            PrimaryFunction::TestLink => self.ack(app),
            PrimaryFunction::UserDataConfirmed => match asdu {
                Some(asdu) => {
                    if app.user_data(asdu, false) {
                        self.ack(app)
                    } else {
                        // Busy: not accepted. The exchange is complete all the same: a
                        // repeat of this frame (our NACK lost) gets the NACK again, and
                        // the primary offers the data anew with the next FCB.
                        self.fixed(SecondaryFunction::NackBusy, app)
                    }
                }
                None => return Some(self.fixed(SecondaryFunction::NotImplemented, app)),
            },
            PrimaryFunction::RequestClass1 => self.class_data(app, true),
            PrimaryFunction::RequestClass2 => {
                let class1_first = self.config.class1_on_class2_request && app.has_class1();
                self.class_data(app, class1_first)
            }
            PrimaryFunction::RequestAccessDemand | PrimaryFunction::Other(_) => {
                return Some(self.fixed(SecondaryFunction::NotImplemented, app));
            }
        };
        if control.fcv() {
            self.last_fcb = Some(control.fcb());
            self.last_response = Some(response.clone());
        }
        Some(response)
    }

    fn class_data(&mut self, app: &mut dyn SecondaryApplication, class1: bool) -> Frame {
        let asdu = if class1 { app.class1() } else { app.class2() };
        match asdu {
            Some(asdu) => Frame::Variable {
                control: Control::secondary(
                    SecondaryFunction::UserData,
                    app.has_class1(),
                    app.data_flow_stopped(),
                ),
                address: self.config.address,
                asdu,
            },
            None => self.no_data(app),
        }
    }

    fn ack(&self, app: &dyn SecondaryApplication) -> Frame {
        if self.config.single_character && !app.has_class1() && !app.data_flow_stopped() {
            Frame::SingleCharacter
        } else {
            self.fixed(SecondaryFunction::Ack, app)
        }
    }

    fn no_data(&self, app: &dyn SecondaryApplication) -> Frame {
        if self.config.single_character && !app.has_class1() && !app.data_flow_stopped() {
            Frame::SingleCharacter
        } else {
            self.fixed(SecondaryFunction::NackNoData, app)
        }
    }

    fn fixed(&self, function: SecondaryFunction, app: &dyn SecondaryApplication) -> Frame {
        Frame::Fixed {
            control: Control::secondary(function, app.has_class1(), app.data_flow_stopped()),
            address: self.config.address,
        }
    }
}
