//! Loopback ports for the peers, stations and servers a test runs.
//!
//! A single port is any free one the kernel hands out ([`free_port`]): bound and released,
//! for a peer that binds it right after. A station's nodes listen on `count` consecutive
//! ports ([`free_port_range`]); those are taken below the kernel's ephemeral range
//! (32768-60999 on Linux): a range found free there can be taken the next moment by any
//! outgoing connection on the machine (the station's own links, another test's clients)
//! before the station listens on it. Each call in this process gets a range of its own,
//! and processes start at different places by their id.

use std::net::{Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicU16, Ordering};
use std::time::{Duration, Instant};

/// A free loopback port, bound and released (a peer binds it right after; or nobody
/// listens on it, for a test of a refused connection).
pub fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// A base port whose next `count` ports are free on loopback, below the ephemeral range.
pub fn free_port_range(count: u16) -> u16 {
    static NEXT: AtomicU16 = AtomicU16::new(0);
    // 20 000 + up to 400 slots of 30 ports: below 32 768.
    let start = 20_000 + u16::try_from(std::process::id() % 400).unwrap_or(0) * 30;
    let _ = NEXT.compare_exchange(0, start, Ordering::SeqCst, Ordering::SeqCst);
    for _ in 0..200 {
        let base = NEXT.fetch_add(count + 1, Ordering::SeqCst);
        if base.checked_add(count).is_none_or(|end| end >= 32_768) {
            NEXT.store(20_000, Ordering::SeqCst);
            continue;
        }
        let free = (0..count)
            .all(|i| TcpListener::bind(SocketAddr::from((Ipv4Addr::LOCALHOST, base + i))).is_ok());
        if free {
            return base;
        }
    }
    panic!("no free port range of {count} below the ephemeral range");
}

/// Whether something listens on the loopback `port` within `within` (asked every 20 ms).
pub fn listening_within(port: u16, within: Duration) -> bool {
    let deadline = Instant::now() + within;
    loop {
        if TcpStream::connect(("127.0.0.1", port)).is_ok() {
            return true;
        }
        if Instant::now() >= deadline {
            return false;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}
