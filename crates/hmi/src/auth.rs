//! Sessions, CSRF tokens, the login rate limit and the bound on password verifications.
//!
//! A session is a random 256-bit token in an HttpOnly, SameSite=Strict cookie; each has
//! its own random CSRF token that every state-changing request must echo in the
//! `X-CSRF-Token` header (a forged cross-site form cannot read it). Sessions end after an
//! idle time ([`SESSION_IDLE`] by default) without use; ending a session (logout, expiry,
//! the user removed or changed) closes its WebSockets, of which it may hold at most
//! [`MAX_SOCKETS_PER_SESSION`].
//!
//! Logins are limited before any password is verified, because each verification costs
//! an argon2 block of 19 MiB:
//! - per client address, an attempt is *reserved* (counted as a failure until it
//!   succeeds) in the same step as it is checked, so a burst of parallel requests cannot
//!   all pass the check; after [`FREE_FAILURES`] failures the address must wait, and the
//!   wait doubles with each further failure (up to [`MAX_ADDRESS_DELAY`]);
//! - per user name, failures from any address slow that name's attempts down by a delay
//!   the server holds the request for (doubling up to [`MAX_NAME_DELAY`]) instead of
//!   refusing them, so that nobody can lock a user out by guessing at its name;
//! - at most [`MAX_CONCURRENT_VERIFICATIONS`] verifications run at once, at most
//!   [`MAX_WAITING_VERIFICATIONS`] wait for one (up to [`VERIFICATION_QUEUE_WAIT`]); any
//!   further request is answered "busy" at once, without allocating anything.

use std::collections::HashMap;
use std::net::IpAddr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use tokio::sync::{watch, Semaphore};

/// A session ends after this long without a request (unless configured otherwise).
pub const SESSION_IDLE: Duration = Duration::from_secs(8 * 3600);
/// WebSockets one session may hold open at once (a browser needs one per tab).
pub const MAX_SOCKETS_PER_SESSION: usize = 8;
/// Failures an address or a name may have before it is slowed down.
pub const FREE_FAILURES: u32 = 5;
/// The first wait of an address after its free failures; it doubles per failure.
pub const FIRST_ADDRESS_DELAY: Duration = Duration::from_secs(5);
/// The longest wait of an address.
pub const MAX_ADDRESS_DELAY: Duration = Duration::from_secs(15 * 60);
/// The first delay of a name after its free failures; it doubles per failure.
pub const FIRST_NAME_DELAY: Duration = Duration::from_millis(250);
/// The longest delay of a name: short enough that its user still gets in.
pub const MAX_NAME_DELAY: Duration = Duration::from_secs(3);
/// Failures are forgotten after this long without one.
pub const FAILURE_MEMORY: Duration = Duration::from_secs(3600);
/// Password verifications running at once (each holds 19 MiB).
pub const MAX_CONCURRENT_VERIFICATIONS: usize = 2;
/// Login requests that may wait for a verification slot.
pub const MAX_WAITING_VERIFICATIONS: usize = 16;
/// How long a login request waits for a verification slot before it is answered busy.
pub const VERIFICATION_QUEUE_WAIT: Duration = Duration::from_secs(5);
/// Entries the limiter keeps before it forgets old ones (bounded memory under a flood).
const MAX_LIMITER_ENTRIES: usize = 100_000;

/// A logged-in user.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Session {
    /// User name.
    pub user: String,
    /// Permission level.
    pub level: u8,
    /// The token the session's requests must carry in `X-CSRF-Token`.
    pub csrf: String,
}

fn random_token() -> String {
    let mut bytes = [0u8; 32];
    rand::fill(&mut bytes);
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Compares two strings in time independent of where they differ.
pub fn constant_time_eq(a: &str, b: &str) -> bool {
    a.len() == b.len()
        && a.bytes()
            .zip(b.bytes())
            .fold(0u8, |acc, (x, y)| acc | (x ^ y))
            == 0
}

#[derive(Debug)]
struct SessionEntry {
    session: Session,
    used: Instant,
    /// Dropped with the entry: every socket of the session watches it and closes then.
    sockets: watch::Sender<()>,
}

/// Why a WebSocket was not opened for a session.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SocketRefusal {
    /// The session is unknown or has ended.
    #[error("not logged in")]
    NoSession,
    /// The session holds [`MAX_SOCKETS_PER_SESSION`] sockets already.
    #[error("too many live connections for this session")]
    TooMany,
}

/// The live sessions.
#[derive(Debug)]
pub struct Sessions {
    map: Mutex<HashMap<String, SessionEntry>>,
    idle: Mutex<Duration>,
}

impl Default for Sessions {
    fn default() -> Self {
        Sessions::new(SESSION_IDLE)
    }
}

impl Sessions {
    /// No sessions; each ends after `idle` without a request.
    pub fn new(idle: Duration) -> Sessions {
        Sessions {
            map: Mutex::default(),
            idle: Mutex::new(idle),
        }
    }

    fn idle(&self) -> Duration {
        *self.idle.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Starts a session; returns its token.
    pub fn create(&self, user: &str, level: u8) -> (String, Session) {
        let token = random_token();
        let session = Session {
            user: user.to_owned(),
            level,
            csrf: random_token(),
        };
        let idle = self.idle();
        let mut map = self.map.lock().unwrap_or_else(|p| p.into_inner());
        let now = Instant::now();
        map.retain(|_, entry| now.duration_since(entry.used) < idle);
        map.insert(
            token.clone(),
            SessionEntry {
                session: session.clone(),
                used: now,
                sockets: watch::channel(()).0,
            },
        );
        (token, session)
    }

    /// The session of a token, refreshed; `None` when unknown or expired.
    pub fn get(&self, token: &str) -> Option<Session> {
        let idle = self.idle();
        let mut map = self.map.lock().unwrap_or_else(|p| p.into_inner());
        let now = Instant::now();
        let entry = map.get_mut(token)?;
        if now.duration_since(entry.used) >= idle {
            map.remove(token);
            return None;
        }
        entry.used = now;
        Some(entry.session.clone())
    }

    /// Registers a WebSocket of the session of `token`: the receiver reports an error
    /// (its sender is gone) once the session ends, and the socket must close then.
    pub fn open_socket(&self, token: &str) -> Result<watch::Receiver<()>, SocketRefusal> {
        let idle = self.idle();
        let map = self.map.lock().unwrap_or_else(|p| p.into_inner());
        let entry = map
            .get(token)
            .filter(|entry| entry.used.elapsed() < idle)
            .ok_or(SocketRefusal::NoSession)?;
        // Counted and added under the one lock: parallel upgrades cannot pass together.
        if entry.sockets.receiver_count() >= MAX_SOCKETS_PER_SESSION {
            return Err(SocketRefusal::TooMany);
        }
        Ok(entry.sockets.subscribe())
    }

    /// Ends a session (its sockets close).
    pub fn remove(&self, token: &str) {
        self.map
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .remove(token);
    }

    /// Ends every session of a user (removed or changed by an administrator).
    pub fn remove_user(&self, user: &str) {
        self.map
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .retain(|_, entry| entry.session.user != user);
    }

    /// Ends the sessions idle for too long (their sockets close); returns how many.
    pub fn sweep(&self) -> usize {
        let idle = self.idle();
        let mut map = self.map.lock().unwrap_or_else(|p| p.into_inner());
        let before = map.len();
        let now = Instant::now();
        map.retain(|_, entry| now.duration_since(entry.used) < idle);
        before - map.len()
    }

    /// Changes how long a session lives without a request.
    pub fn set_idle(&self, idle: Duration) {
        *self.idle.lock().unwrap_or_else(|p| p.into_inner()) = idle;
    }
}

#[derive(Debug, Clone, Copy)]
struct Attempts {
    /// Failed attempts, including those still being verified.
    failures: u32,
    /// Attempts being verified now.
    pending: u32,
    /// When the last failure was counted.
    last: Instant,
}

impl Attempts {
    fn new(now: Instant) -> Attempts {
        Attempts {
            failures: 0,
            pending: 0,
            last: now,
        }
    }
}

/// `first * 2^(failures - FREE_FAILURES)`, capped; zero within the free failures.
fn progressive(failures: u32, first: Duration, max: Duration) -> Duration {
    match failures.checked_sub(FREE_FAILURES) {
        None => Duration::ZERO,
        Some(extra) => first
            .checked_mul(1u32 << extra.min(20))
            .unwrap_or(max)
            .min(max),
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Settled {
    Succeeded,
    Failed,
    /// Not tried after all (the server was busy): not the client's failure.
    Abandoned,
}

/// Why a login was not even tried.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum LoginRefusal {
    /// The client address must wait this long.
    #[error("too many failed logins; try again later")]
    TooManyFailures(Duration),
}

/// Counts failed logins per client address and per user name.
#[derive(Debug, Default)]
pub struct LoginLimiter {
    addresses: Mutex<HashMap<IpAddr, Attempts>>,
    names: Mutex<HashMap<String, Attempts>>,
}

/// A reserved login attempt; it counts as a failure unless [`LoginAttempt::succeeded`]
/// or [`LoginAttempt::failed`] settles it (a dropped request stays a failure).
#[derive(Debug)]
pub struct LoginAttempt {
    limiter: Arc<LoginLimiter>,
    address: IpAddr,
    name: String,
    /// How long the server holds this attempt before verifying it (the name's delay).
    pub delay: Duration,
    settled: bool,
}

impl LoginLimiter {
    /// Checks and reserves an attempt of `name` from `address` in one step.
    pub fn begin(
        self: &Arc<Self>,
        address: IpAddr,
        name: &str,
    ) -> Result<LoginAttempt, LoginRefusal> {
        let now = Instant::now();
        {
            let mut addresses = self.addresses.lock().unwrap_or_else(|p| p.into_inner());
            forget_old(&mut addresses, now);
            let entry = addresses
                .entry(address)
                .or_insert_with(|| Attempts::new(now));
            let settled_failures = entry.failures.saturating_sub(entry.pending);
            let free = entry.failures < FREE_FAILURES;
            let waited = entry.pending == 0
                && now.duration_since(entry.last)
                    >= progressive(settled_failures, FIRST_ADDRESS_DELAY, MAX_ADDRESS_DELAY);
            if !free && !waited {
                let wait = progressive(
                    settled_failures.max(FREE_FAILURES),
                    FIRST_ADDRESS_DELAY,
                    MAX_ADDRESS_DELAY,
                )
                .saturating_sub(now.duration_since(entry.last));
                return Err(LoginRefusal::TooManyFailures(
                    wait.max(Duration::from_secs(1)),
                ));
            }
            entry.failures += 1;
            entry.pending += 1;
            entry.last = now;
        }
        // No user name is longer (users::valid_name): longer keys would only cost memory.
        let name_key: String = name.chars().take(64).collect();
        let delay = {
            let mut names = self.names.lock().unwrap_or_else(|p| p.into_inner());
            forget_old(&mut names, now);
            let failures = names.get(&name_key).map_or(0, |entry| entry.failures);
            progressive(failures, FIRST_NAME_DELAY, MAX_NAME_DELAY)
        };
        Ok(LoginAttempt {
            limiter: Arc::clone(self),
            address,
            name: name_key,
            delay,
            settled: false,
        })
    }

    fn settle(&self, address: IpAddr, name: &str, settled: Settled) {
        let now = Instant::now();
        {
            let mut addresses = self.addresses.lock().unwrap_or_else(|p| p.into_inner());
            match (settled, addresses.get_mut(&address)) {
                (Settled::Succeeded, _) => {
                    addresses.remove(&address);
                }
                (Settled::Failed, Some(entry)) => {
                    entry.pending = entry.pending.saturating_sub(1);
                    entry.last = now;
                }
                (Settled::Abandoned, Some(entry)) => {
                    entry.pending = entry.pending.saturating_sub(1);
                    entry.failures = entry.failures.saturating_sub(1);
                }
                (_, None) => {}
            }
        }
        let mut names = self.names.lock().unwrap_or_else(|p| p.into_inner());
        if settled == Settled::Succeeded {
            names.remove(name);
        } else if settled == Settled::Failed {
            let entry = names
                .entry(name.to_owned())
                .or_insert_with(|| Attempts::new(now));
            entry.failures = entry.failures.saturating_add(1);
            entry.last = now;
        }
    }
}

fn forget_old<K>(map: &mut HashMap<K, Attempts>, now: Instant) {
    if map.len() >= MAX_LIMITER_ENTRIES {
        map.retain(|_, entry| entry.pending > 0 || now.duration_since(entry.last) < FAILURE_MEMORY);
    }
}

impl LoginAttempt {
    /// The password was right: the address and the name start afresh.
    pub fn succeeded(mut self) {
        self.settled = true;
        self.limiter
            .settle(self.address, &self.name, Settled::Succeeded);
    }

    /// The password was not verified after all (the server was busy).
    pub fn abandoned(mut self) {
        self.settled = true;
        self.limiter
            .settle(self.address, &self.name, Settled::Abandoned);
    }

    /// The password was wrong.
    pub fn failed(mut self) {
        self.settled = true;
        self.limiter
            .settle(self.address, &self.name, Settled::Failed);
    }
}

impl Drop for LoginAttempt {
    fn drop(&mut self) {
        if !self.settled {
            self.limiter
                .settle(self.address, &self.name, Settled::Failed);
        }
    }
}

/// No verification slot became free in time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the server is busy verifying other logins; try again shortly")]
pub struct VerifierBusy;

type Job = Box<dyn FnOnce() + Send>;

/// Bounds the password verifications running at once (each costs 19 MiB of argon2).
///
/// They run on [`MAX_CONCURRENT_VERIFICATIONS`] threads of their own rather than on
/// tokio's blocking pool: the allocator keeps a memory arena per thread, and hundreds of
/// pool threads would each keep a freed 19 MiB block resident.
pub struct Verifier {
    slots: Arc<Semaphore>,
    waiting: AtomicUsize,
    running: Arc<AtomicUsize>,
    most_running: Arc<AtomicUsize>,
    jobs: Mutex<std::sync::mpsc::Sender<Job>>,
}

impl std::fmt::Debug for Verifier {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Verifier")
            .field("running", &self.running)
            .field("most_running", &self.most_running)
            .finish_non_exhaustive()
    }
}

impl Default for Verifier {
    fn default() -> Self {
        let (jobs, queue) = std::sync::mpsc::channel::<Job>();
        let queue = Arc::new(Mutex::new(queue));
        for index in 0..MAX_CONCURRENT_VERIFICATIONS {
            let queue = Arc::clone(&queue);
            // The threads end when the verifier (the only sender) is dropped.
            let spawned = std::thread::Builder::new()
                .name(format!("hmi-verify-{index}"))
                .spawn(move || loop {
                    let job = queue.lock().unwrap_or_else(|p| p.into_inner()).recv();
                    match job {
                        Ok(job) => job(),
                        Err(_) => return,
                    }
                });
            if let Err(error) = spawned {
                tracing::error!(%error, "cannot start a password verification thread");
            }
        }
        Verifier {
            slots: Arc::new(Semaphore::new(MAX_CONCURRENT_VERIFICATIONS)),
            waiting: AtomicUsize::new(0),
            running: Arc::default(),
            most_running: Arc::default(),
            jobs: Mutex::new(jobs),
        }
    }
}

struct Waiting<'a>(&'a AtomicUsize);

impl Drop for Waiting<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::AcqRel);
    }
}

impl Verifier {
    /// Runs `verify` on a verification thread once a slot is free. The slot is held by
    /// the computation itself, so a client that goes away cannot free it early.
    pub async fn run<T: Send + 'static>(
        &self,
        verify: impl FnOnce() -> T + Send + 'static,
    ) -> Result<T, VerifierBusy> {
        if self.waiting.fetch_add(1, Ordering::AcqRel) >= MAX_WAITING_VERIFICATIONS {
            self.waiting.fetch_sub(1, Ordering::AcqRel);
            return Err(VerifierBusy);
        }
        let waiting = Waiting(&self.waiting);
        let permit = tokio::time::timeout(
            VERIFICATION_QUEUE_WAIT,
            Arc::clone(&self.slots).acquire_owned(),
        )
        .await
        .map_err(|_| VerifierBusy)?
        .map_err(|_| VerifierBusy)?;
        drop(waiting);
        let running = Arc::clone(&self.running);
        let most = Arc::clone(&self.most_running);
        let (done, result) = tokio::sync::oneshot::channel();
        let job: Job = Box::new(move || {
            let now = running.fetch_add(1, Ordering::AcqRel) + 1;
            most.fetch_max(now, Ordering::AcqRel);
            let verified = verify();
            running.fetch_sub(1, Ordering::AcqRel);
            drop(permit);
            let _ = done.send(verified);
        });
        self.jobs
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .send(job)
            .map_err(|_| VerifierBusy)?;
        result.await.map_err(|_| VerifierBusy)
    }

    /// The most verifications that ever ran at once (a health figure, and what the
    /// attack tests check against [`MAX_CONCURRENT_VERIFICATIONS`]).
    pub fn most_running(&self) -> usize {
        self.most_running.load(Ordering::Acquire)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sessions_have_distinct_tokens_and_end() {
        let sessions = Sessions::default();
        let (a, sa) = sessions.create("op", 5);
        let (b, _) = sessions.create("op", 5);
        assert_ne!(a, b);
        assert_eq!(a.len(), 64);
        assert_eq!(sessions.get(&a), Some(sa));
        sessions.remove(&a);
        assert!(sessions.get(&a).is_none());
        sessions.remove_user("op");
        assert!(sessions.get(&b).is_none());
    }

    #[test]
    fn sockets_are_capped_and_closed_with_their_session() {
        let sessions = Sessions::default();
        let (token, _) = sessions.create("op", 5);
        let sockets: Vec<_> = (0..MAX_SOCKETS_PER_SESSION)
            .map(|_| sessions.open_socket(&token).unwrap())
            .collect();
        assert_eq!(
            sessions.open_socket(&token).unwrap_err(),
            SocketRefusal::TooMany
        );
        sessions.remove(&token);
        assert!(sockets.iter().all(|s| s.has_changed().is_err()));
        assert_eq!(
            sessions.open_socket(&token).unwrap_err(),
            SocketRefusal::NoSession
        );
    }

    #[test]
    fn parallel_attempts_are_reserved_before_verification() {
        let limiter = Arc::new(LoginLimiter::default());
        let address: IpAddr = [127, 0, 0, 1].into();
        let held: Vec<_> = (0..FREE_FAILURES)
            .map(|_| limiter.begin(address, "operator").unwrap())
            .collect();
        // Nothing settled yet, and still the next one is refused.
        assert!(limiter.begin(address, "operator").is_err());
        drop(held);
        assert!(limiter.begin(address, "operator").is_err());
        // Another address may try the same name: it is delayed, not locked out.
        let other = limiter.begin([127, 0, 0, 3].into(), "operator").unwrap();
        assert!(other.delay > Duration::ZERO && other.delay <= MAX_NAME_DELAY);
        other.succeeded();
        let after = limiter.begin([127, 0, 0, 3].into(), "operator").unwrap();
        assert_eq!(after.delay, Duration::ZERO);
    }

    #[test]
    fn delays_grow_and_are_capped() {
        assert_eq!(
            progressive(FREE_FAILURES - 1, FIRST_NAME_DELAY, MAX_NAME_DELAY),
            Duration::ZERO
        );
        assert_eq!(
            progressive(FREE_FAILURES, FIRST_ADDRESS_DELAY, MAX_ADDRESS_DELAY),
            FIRST_ADDRESS_DELAY
        );
        assert_eq!(
            progressive(FREE_FAILURES + 1, FIRST_ADDRESS_DELAY, MAX_ADDRESS_DELAY),
            FIRST_ADDRESS_DELAY * 2
        );
        assert_eq!(
            progressive(1000, FIRST_NAME_DELAY, MAX_NAME_DELAY),
            MAX_NAME_DELAY
        );
    }

    #[test]
    fn constant_time_comparison() {
        assert!(constant_time_eq("abc", "abc"));
        assert!(!constant_time_eq("abc", "abd"));
        assert!(!constant_time_eq("abc", "abcd"));
    }
}
