//! A process's console: standard input's lines for the commands that take operations
//! while they run (`stanice run`, `stanice iec103 relay`).

use std::io::BufRead as _;

/// Standard input's lines, read on a thread of their own.
///
/// Not `tokio::io::stdin`: it reads on the runtime's blocking pool, and the runtime waits
/// for that read when it shuts down, so Ctrl-C stopped the station only once Enter was
/// pressed. A plain thread blocked in `read` does not hold up the process's exit.
pub(crate) fn stdin_lines() -> tokio::sync::mpsc::Receiver<String> {
    let (sender, receiver) = tokio::sync::mpsc::channel(16);
    let spawned = std::thread::Builder::new()
        .name("console".to_owned())
        .spawn(move || {
            for line in std::io::stdin().lock().lines() {
                let Ok(line) = line else { break };
                if sender.blocking_send(line).is_err() {
                    break;
                }
            }
        });
    if let Err(error) = spawned {
        // The station runs on without its console (the receiver sees a closed channel).
        eprintln!("warning: no console: {error}");
    }
    receiver
}

/// Writes lines to standard output; false once it is closed (a broken pipe: `| head`),
/// when a command-line tool stops quietly.
pub(crate) fn print_lines(lines: &[String]) -> bool {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    lines.iter().all(|line| writeln!(out, "{line}").is_ok()) && out.flush().is_ok()
}

/// Resolves after `duration` (a `--duration` option), never without one.
pub(crate) async fn run_for(duration: Option<f64>) {
    match duration {
        Some(seconds) => {
            tokio::time::sleep(std::time::Duration::from_secs_f64(seconds.clamp(0.0, 1e9))).await
        }
        None => std::future::pending().await,
    }
}
