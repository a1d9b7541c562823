//! What `stanice run` says when a node's port is taken: which project and node wanted
//! it, which program holds it (on Linux, from `/proc`), and a `--port-base` that is free.
//!
//! Two examples started at once (each with the default port base 2404) collided with a
//! doubled error and no hint; a person then had to find the other process and guess a
//! base whose every port is free.

use std::net::{SocketAddr, TcpListener};

use station::config::Project;

/// The message for a node of `project` that cannot listen on `address`.
pub(crate) fn explain(project: &Project, node: &str, address: SocketAddr) -> String {
    let holder = port_holder(address.port())
        .map(|holder| format!(" (held by {holder})"))
        .unwrap_or_default();
    let mut text = format!(
        "project `{}` ({}): node `{node}` cannot listen on {address}: the port is in use{holder}",
        project.station.name,
        project.folder.display()
    );
    let offsets: Vec<u16> = project
        .nodes
        .iter()
        .filter_map(|node| node.server.as_ref().map(|server| server.port_offset))
        .collect();
    match free_port_base(project, address.ip(), &offsets) {
        Some(base) => text.push_str(&format!(
            "; run it on other ports with --port-base {base} (its servers then listen on {base}..{})",
            base + offsets.iter().copied().max().unwrap_or(0)
        )),
        None => text.push_str("; run it on other ports with --port-base N"),
    }
    text
}

/// A port base, in steps of 100 above the project's, at which every server of the
/// project could listen now on `ip` (the station's `bind`, or the node's host when a hosts
/// file puts it on one).
fn free_port_base(project: &Project, ip: std::net::IpAddr, offsets: &[u16]) -> Option<u16> {
    let span = offsets.iter().copied().max().unwrap_or(0);
    (1..=100u16)
        .filter_map(|step| project.station.port_base.checked_add(step * 100))
        .filter(|base| base.checked_add(span).is_some())
        .find(|base| {
            offsets
                .iter()
                .all(|offset| TcpListener::bind(SocketAddr::new(ip, base + offset)).is_ok())
        })
}

/// The program listening on TCP `port`, as `process PID (COMMAND LINE)`; `None` where
/// `/proc` does not tell (another system, another user's process).
fn port_holder(port: u16) -> Option<String> {
    let inode = ["/proc/net/tcp", "/proc/net/tcp6"]
        .iter()
        .filter_map(|table| std::fs::read_to_string(table).ok())
        .find_map(|table| listening_inode(&table, port))?;
    let socket = format!("socket:[{inode}]");
    for process in std::fs::read_dir("/proc").ok()?.flatten() {
        let Some(pid) = process
            .file_name()
            .to_str()
            .and_then(|n| n.parse::<u32>().ok())
        else {
            continue;
        };
        let Ok(descriptors) = std::fs::read_dir(process.path().join("fd")) else {
            continue;
        };
        let holds = descriptors.flatten().any(|fd| {
            std::fs::read_link(fd.path()).is_ok_and(|link| link.as_os_str() == socket.as_str())
        });
        if holds {
            let command = std::fs::read(process.path().join("cmdline"))
                .map(|bytes| {
                    bytes
                        .split(|&b| b == 0)
                        .filter(|part| !part.is_empty())
                        .map(|part| String::from_utf8_lossy(part).into_owned())
                        .collect::<Vec<_>>()
                        .join(" ")
                })
                .unwrap_or_default();
            return Some(format!("process {pid}: {command}"));
        }
    }
    None
}

/// The socket inode of the listening socket on `port` in a `/proc/net/tcp` table.
fn listening_inode(table: &str, port: u16) -> Option<u64> {
    const LISTEN: &str = "0A";
    table.lines().skip(1).find_map(|line| {
        let fields: Vec<&str> = line.split_whitespace().collect();
        let local = fields.get(1)?;
        let (_, local_port) = local.rsplit_once(':')?;
        let listening = u16::from_str_radix(local_port, 16).ok()? == port
            && fields.get(3).copied() == Some(LISTEN);
        if listening {
            fields.get(9)?.parse().ok()
        } else {
            None
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_listening_socket_of_a_port() {
        let table = "  sl  local_address rem_address   st tx_queue rx_queue tr tm->when retrnsmt   uid  timeout inode\n\
   0: 0100007F:096E 00000000:0000 0A 00000000:00000000 00:00000000 00000000     0        0 123456 1 0000000000000000 100 0 0 10 0\n\
   1: 0100007F:096E 0100007F:9C40 01 00000000:00000000 00:00000000 00000000     0        0 654321 1 0000000000000000 20 4 30 10 -1\n";
        assert_eq!(listening_inode(table, 2414), Some(123456));
        assert_eq!(listening_inode(table, 2404), None);
    }

    #[test]
    fn names_this_process_as_the_holder_of_its_listener() {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap_or_else(|e| panic!("{e}"));
        let port = listener.local_addr().map(|a| a.port()).unwrap_or_default();
        if std::path::Path::new("/proc/net/tcp").exists() {
            let holder = port_holder(port).unwrap_or_default();
            assert!(
                holder.contains(&format!("process {}", std::process::id())),
                "{holder}"
            );
        }
    }
}
