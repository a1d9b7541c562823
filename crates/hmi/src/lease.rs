//! The operator lease of a remote lab: one controlling user at a time, everyone else
//! observes (the sorting-lab thesis, section 11: the reservation system let only the user
//! holding the current booking connect; WebLab-Deusto and GOLDi keep the same rule).
//!
//! A screens folder with a `[lease]` table in `hmi.toml` turns it on. Then every control
//! needs the lease besides its level:
//!
//! - **Take** (`POST /api/lease`): a user of the operator level or above takes the lease
//!   when nobody holds it and nobody else's booking covers the instant. It ends at the end
//!   of the user's own booking when one covers the instant, else at the start of the next
//!   booking of someone else, and in any case after `idle_minutes` without a control.
//! - **Release** by its holder, **revoke** by an administrator (`admin_level`).
//! - **Bookings**: slots of `slot_minutes` on the slot grid (from midnight UTC), at most
//!   `max_slots` in a row, never overlapping; booked by operators, cancelled by their
//!   owner or an administrator; kept in `bookings.json` beside `hmi.toml`.
//!
//! Every instant is passed in: [`LeaseDesk`] reads no clock, so the rules are tested
//! exactly; the web layer gives it `Utc::now()` on each request, so a lease that ran out
//! is over at the very instant anyone looks (within the browser's 1-s poll).

use std::path::{Path, PathBuf};

use chrono::{DateTime, Duration, DurationRound as _, Utc};
use serde::{Deserialize, Serialize};

/// `[lease]` of `hmi.toml`.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LeaseConfig {
    /// The lowest level that may take the lease and book (the operators).
    #[serde(default = "operator_level")]
    pub level: u8,
    /// The lowest level that may revoke a lease and cancel anyone's booking.
    #[serde(default = "admin_level")]
    pub admin_level: u8,
    /// A lease without a control for this long ends.
    #[serde(default = "idle_minutes")]
    pub idle_minutes: u32,
    /// The booking grid.
    #[serde(default = "slot_minutes")]
    pub slot_minutes: u32,
    /// The longest booking, in slots.
    #[serde(default = "max_slots")]
    pub max_slots: u32,
}

fn operator_level() -> u8 {
    5
}
fn admin_level() -> u8 {
    9
}
fn idle_minutes() -> u32 {
    10
}
fn slot_minutes() -> u32 {
    30
}
fn max_slots() -> u32 {
    4
}

impl Default for LeaseConfig {
    fn default() -> LeaseConfig {
        LeaseConfig {
            level: operator_level(),
            admin_level: admin_level(),
            idle_minutes: idle_minutes(),
            slot_minutes: slot_minutes(),
            max_slots: max_slots(),
        }
    }
}

/// A booked time slot.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Booking {
    /// Its number.
    pub id: u64,
    /// Who booked it.
    pub user: String,
    /// From.
    pub start: DateTime<Utc>,
    /// To (exclusive).
    pub end: DateTime<Utc>,
}

/// The lease as it is.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Lease {
    /// Who holds it.
    pub holder: String,
    /// Since when.
    pub since: DateTime<Utc>,
    /// When it ends unless released: the booking's end or the next one's start.
    pub ends: Option<DateTime<Utc>>,
    /// When it ends if no control comes first.
    pub idle_until: DateTime<Utc>,
}

impl Lease {
    /// The instant it ends (the earlier of its end and its idle limit).
    pub fn until(&self) -> DateTime<Utc> {
        self.ends
            .map_or(self.idle_until, |e| e.min(self.idle_until))
    }
}

/// Why the desk said no.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LeaseRefusal {
    /// The user's level is below the operators'.
    #[error("observers cannot take control: level {needed} needed, you have {has}")]
    Level {
        /// Needed.
        needed: u8,
        /// Had.
        has: u8,
    },
    /// Someone else holds it.
    #[error("the lab is controlled by {holder} until {until}")]
    Held {
        /// Who.
        holder: String,
        /// Until when (RFC 3339).
        until: String,
    },
    /// Someone else's booking covers the instant.
    #[error("the lab is booked by {user} until {until}")]
    Booked {
        /// Who.
        user: String,
        /// Until when (RFC 3339).
        until: String,
    },
    /// A control or release by a user who does not hold the lease.
    #[error("you do not hold the lab's control lease; take it first")]
    NotHolder,
    /// Only an administrator may do that.
    #[error("only an administrator may do that (level {needed})")]
    NotAdmin {
        /// Needed.
        needed: u8,
    },
    /// A booking that is not on the grid, too long, in the past or overlapping.
    #[error("{0}")]
    BadBooking(String),
    /// No booking has that number.
    #[error("no booking {0}")]
    NoBooking(u64),
    /// The bookings file cannot be written.
    #[error("the bookings cannot be saved: {0}")]
    Save(String),
}

/// The lease and the bookings.
#[derive(Debug)]
pub struct LeaseDesk {
    config: LeaseConfig,
    lease: Option<Lease>,
    bookings: Vec<Booking>,
    next_id: u64,
    /// Where the bookings are kept (`None`: in memory only).
    file: Option<PathBuf>,
}

/// The desk's state for a user, as `GET /api/lease` gives it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct LeaseView {
    /// The lease, if anyone holds it.
    pub lease: Option<Lease>,
    /// The asking user holds it.
    pub yours: bool,
    /// The asking user may take it now.
    pub can_take: bool,
    /// The asking user may revoke it.
    pub can_revoke: bool,
    /// The booking covering now, if any.
    pub current_booking: Option<Booking>,
    /// The bookings that have not ended, in order.
    pub bookings: Vec<Booking>,
    /// The grid.
    pub slot_minutes: u32,
    /// The longest booking, in slots.
    pub max_slots: u32,
}

impl LeaseDesk {
    /// A desk with the bookings of `file` (none when it does not exist yet).
    pub fn open(config: LeaseConfig, file: Option<&Path>) -> Result<LeaseDesk, String> {
        let bookings: Vec<Booking> = match file {
            Some(path) if path.exists() => {
                let text = std::fs::read_to_string(path)
                    .map_err(|e| format!("{}: {e}", path.display()))?;
                serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?
            }
            _ => Vec::new(),
        };
        let next_id = bookings.iter().map(|b| b.id).max().unwrap_or(0) + 1;
        Ok(LeaseDesk {
            config,
            lease: None,
            bookings,
            next_id,
            file: file.map(Path::to_path_buf),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &LeaseConfig {
        &self.config
    }

    fn idle(&self) -> Duration {
        Duration::minutes(i64::from(self.config.idle_minutes.max(1)))
    }

    fn booking_at(&self, now: DateTime<Utc>) -> Option<&Booking> {
        self.bookings.iter().find(|b| b.start <= now && now < b.end)
    }

    /// Ends the lease if its time is up at `now`; the holder whose lease ended.
    pub fn expire(&mut self, now: DateTime<Utc>) -> Option<String> {
        let over = self.lease.as_ref().is_some_and(|l| now >= l.until());
        if over {
            return self.lease.take().map(|l| l.holder);
        }
        None
    }

    /// The lease now (after expiry).
    pub fn lease(&mut self, now: DateTime<Utc>) -> Option<&Lease> {
        self.expire(now);
        self.lease.as_ref()
    }

    /// What `user` (at `level`) sees at `now`.
    pub fn view(&mut self, user: &str, level: u8, now: DateTime<Utc>) -> LeaseView {
        self.expire(now);
        let current = self.booking_at(now).cloned();
        let can_take = level >= self.config.level
            && self.lease.as_ref().is_none_or(|l| l.holder == user)
            && current.as_ref().is_none_or(|b| b.user == user);
        LeaseView {
            yours: self.lease.as_ref().is_some_and(|l| l.holder == user),
            can_take,
            can_revoke: level >= self.config.admin_level && self.lease.is_some(),
            lease: self.lease.clone(),
            current_booking: current,
            bookings: self
                .bookings
                .iter()
                .filter(|b| b.end > now)
                .cloned()
                .collect(),
            slot_minutes: self.config.slot_minutes,
            max_slots: self.config.max_slots,
        }
    }

    /// `user` takes the lease at `now`.
    pub fn take(
        &mut self,
        user: &str,
        level: u8,
        now: DateTime<Utc>,
    ) -> Result<Lease, LeaseRefusal> {
        self.expire(now);
        if level < self.config.level {
            return Err(LeaseRefusal::Level {
                needed: self.config.level,
                has: level,
            });
        }
        if let Some(lease) = &self.lease {
            if lease.holder != user {
                return Err(LeaseRefusal::Held {
                    holder: lease.holder.clone(),
                    until: lease.until().to_rfc3339(),
                });
            }
        }
        let ends = match self.booking_at(now) {
            Some(booking) if booking.user != user => {
                return Err(LeaseRefusal::Booked {
                    user: booking.user.clone(),
                    until: booking.end.to_rfc3339(),
                })
            }
            Some(own) => Some(own.end),
            None => self
                .bookings
                .iter()
                .filter(|b| b.start > now && b.user != user)
                .map(|b| b.start)
                .min(),
        };
        let lease = Lease {
            holder: user.to_owned(),
            since: self.lease.as_ref().map_or(now, |l| l.since),
            ends,
            idle_until: now + self.idle(),
        };
        self.lease = Some(lease.clone());
        Ok(lease)
    }

    /// A control by `user` at `now`: allowed only to the holder, whose idle time starts
    /// again.
    pub fn control(&mut self, user: &str, now: DateTime<Utc>) -> Result<(), LeaseRefusal> {
        self.expire(now);
        let idle = self.idle();
        match &mut self.lease {
            Some(lease) if lease.holder == user => {
                lease.idle_until = now + idle;
                Ok(())
            }
            Some(lease) => Err(LeaseRefusal::Held {
                holder: lease.holder.clone(),
                until: lease.until().to_rfc3339(),
            }),
            None => Err(LeaseRefusal::NotHolder),
        }
    }

    /// `user` gives the lease back.
    pub fn release(&mut self, user: &str, now: DateTime<Utc>) -> Result<(), LeaseRefusal> {
        self.expire(now);
        match &self.lease {
            Some(lease) if lease.holder == user => {
                self.lease = None;
                Ok(())
            }
            _ => Err(LeaseRefusal::NotHolder),
        }
    }

    /// An administrator ends the lease; whose it was.
    pub fn revoke(
        &mut self,
        level: u8,
        now: DateTime<Utc>,
    ) -> Result<Option<String>, LeaseRefusal> {
        if level < self.config.admin_level {
            return Err(LeaseRefusal::NotAdmin {
                needed: self.config.admin_level,
            });
        }
        self.expire(now);
        Ok(self.lease.take().map(|l| l.holder))
    }

    /// `user` books `[start, end)`.
    pub fn book(
        &mut self,
        user: &str,
        level: u8,
        start: DateTime<Utc>,
        end: DateTime<Utc>,
        now: DateTime<Utc>,
    ) -> Result<Booking, LeaseRefusal> {
        if level < self.config.level {
            return Err(LeaseRefusal::Level {
                needed: self.config.level,
                has: level,
            });
        }
        let slot = Duration::minutes(i64::from(self.config.slot_minutes.max(1)));
        let on_grid = |t: DateTime<Utc>| t.duration_trunc(slot).is_ok_and(|g| g == t);
        if !on_grid(start) || !on_grid(end) {
            return Err(LeaseRefusal::BadBooking(format!(
                "a booking starts and ends on the {}-minute grid (…:00, …:{:02})",
                self.config.slot_minutes,
                self.config.slot_minutes % 60
            )));
        }
        if end <= start {
            return Err(LeaseRefusal::BadBooking(
                "a booking ends after it starts".into(),
            ));
        }
        if end <= now {
            return Err(LeaseRefusal::BadBooking("that time is over".into()));
        }
        if end - start > slot * i32::try_from(self.config.max_slots.max(1)).unwrap_or(1) {
            return Err(LeaseRefusal::BadBooking(format!(
                "at most {} slots of {} minutes in a row",
                self.config.max_slots, self.config.slot_minutes
            )));
        }
        if let Some(other) = self
            .bookings
            .iter()
            .find(|b| b.start < end && start < b.end)
        {
            return Err(LeaseRefusal::BadBooking(format!(
                "{} has booked {} to {}",
                other.user,
                other.start.to_rfc3339(),
                other.end.to_rfc3339()
            )));
        }
        let booking = Booking {
            id: self.next_id,
            user: user.to_owned(),
            start,
            end,
        };
        self.next_id += 1;
        self.bookings.retain(|b| b.end > now);
        self.bookings.push(booking.clone());
        self.bookings.sort_by_key(|b| b.start);
        // A lease of someone else now ends where this booking starts.
        if let Some(lease) = &mut self.lease {
            if lease.holder != user && start >= now {
                lease.ends = Some(lease.ends.map_or(start, |e| e.min(start)));
            }
        }
        self.save()?;
        Ok(booking)
    }

    /// `user` (or an administrator) cancels booking `id`.
    pub fn cancel(&mut self, user: &str, level: u8, id: u64) -> Result<(), LeaseRefusal> {
        let index = self
            .bookings
            .iter()
            .position(|b| b.id == id)
            .ok_or(LeaseRefusal::NoBooking(id))?;
        let owner = self.bookings.get(index).is_some_and(|b| b.user == user);
        if !owner && level < self.config.admin_level {
            return Err(LeaseRefusal::NotAdmin {
                needed: self.config.admin_level,
            });
        }
        self.bookings.remove(index);
        self.save()
    }

    fn save(&self) -> Result<(), LeaseRefusal> {
        let Some(path) = &self.file else {
            return Ok(());
        };
        let text = serde_json::to_string_pretty(&self.bookings)
            .map_err(|e| LeaseRefusal::Save(e.to_string()))?;
        // Written aside and renamed: a crash leaves the old file or the new, never half.
        let partial = path.with_extension("json.partial");
        std::fs::write(&partial, text)
            .and_then(|()| std::fs::rename(&partial, path))
            .map_err(|e| LeaseRefusal::Save(format!("{}: {e}", path.display())))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(minutes: i64) -> DateTime<Utc> {
        // a whole half hour (1_800_000_000 is a multiple of 1800)
        DateTime::from_timestamp(1_800_000_000, 0).unwrap() + Duration::minutes(minutes)
    }

    fn desk() -> LeaseDesk {
        LeaseDesk::open(LeaseConfig::default(), None).unwrap()
    }

    #[test]
    fn one_holder_at_a_time_observers_never() {
        let mut desk = desk();
        assert!(matches!(
            desk.take("watcher", 1, at(0)),
            Err(LeaseRefusal::Level { .. })
        ));
        desk.take("alice", 5, at(0)).unwrap();
        let refused = desk.take("bob", 5, at(1)).unwrap_err();
        assert!(
            refused.to_string().contains("controlled by alice"),
            "{refused}"
        );
        assert!(desk.control("bob", at(1)).is_err());
        desk.control("alice", at(1)).unwrap();
        assert_eq!(desk.release("bob", at(2)), Err(LeaseRefusal::NotHolder));
        desk.release("alice", at(2)).unwrap();
        desk.take("bob", 5, at(3)).unwrap();
        assert!(desk.view("alice", 5, at(3)).lease.is_some());
        assert!(!desk.view("alice", 5, at(3)).can_take);
    }

    #[test]
    fn an_idle_lease_ends_and_a_control_keeps_it() {
        let mut desk = desk();
        desk.take("alice", 5, at(0)).unwrap();
        desk.control("alice", at(8)).unwrap();
        assert!(desk.lease(at(17)).is_some(), "idle from minute 8");
        assert_eq!(desk.expire(at(18)), Some("alice".into()));
        assert!(desk.lease(at(18)).is_none());
        assert_eq!(desk.control("alice", at(18)), Err(LeaseRefusal::NotHolder));
    }

    #[test]
    fn bookings_decide_who_may_take_it_and_when_it_ends() {
        let mut desk = desk();
        // Off the grid, too long, overlapping: refused in words.
        assert!(desk.book("alice", 5, at(10), at(40), at(0)).is_err());
        assert!(desk.book("alice", 5, at(30), at(30 + 150), at(0)).is_err());
        let booking = desk.book("alice", 5, at(30), at(90), at(0)).unwrap();
        let overlap = desk.book("bob", 5, at(60), at(120), at(0)).unwrap_err();
        assert!(
            overlap.to_string().contains("alice has booked"),
            "{overlap}"
        );
        assert!(desk.book("watcher", 1, at(120), at(150), at(0)).is_err());
        // Bob may control before alice's slot; his lease ends where it starts.
        let lease = desk.take("bob", 5, at(5)).unwrap();
        assert_eq!(lease.ends, Some(at(30)));
        desk.control("bob", at(14)).unwrap();
        desk.control("bob", at(23)).unwrap();
        assert!(desk.lease(at(29)).is_some());
        assert!(desk.lease(at(30)).is_none(), "ended at the booking's start");
        // In alice's slot only alice takes it, and it ends with the slot.
        assert!(matches!(
            desk.take("bob", 5, at(31)),
            Err(LeaseRefusal::Booked { .. })
        ));
        let lease = desk.take("alice", 5, at(31)).unwrap();
        assert_eq!(lease.ends, Some(at(90)));
        // An administrator revokes; the owner or an administrator cancels.
        assert!(desk.revoke(5, at(32)).is_err());
        assert_eq!(desk.revoke(9, at(32)).unwrap(), Some("alice".into()));
        assert!(desk.cancel("bob", 5, booking.id).is_err());
        desk.cancel("admin", 9, booking.id).unwrap();
        desk.take("bob", 5, at(33)).unwrap();
    }

    #[test]
    fn bookings_survive_a_restart() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("bookings.json");
        let mut desk = LeaseDesk::open(LeaseConfig::default(), Some(&file)).unwrap();
        desk.book("alice", 5, at(30), at(60), at(0)).unwrap();
        let mut again = LeaseDesk::open(LeaseConfig::default(), Some(&file)).unwrap();
        assert_eq!(again.view("bob", 5, at(0)).bookings.len(), 1);
        let second = again.book("bob", 5, at(60), at(90), at(0)).unwrap();
        assert_eq!(second.id, 2);
    }
}
