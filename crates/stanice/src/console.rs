//! A process's console: standard input's lines for the commands that take operations
//! while they run (`stanice run`, `stanice iec103 relay`, `stanice lift simulate`).

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
pub(crate) async fn run_for(duration: Option<std::time::Duration>) {
    match duration {
        Some(duration) => tokio::time::sleep(duration).await,
        None => std::future::pending().await,
    }
}

/// Serves a simulated device until it stops by itself, `duration` (a `--duration` option)
/// ends, or Ctrl-C or SIGTERM arrives: the end of every simulator command.
pub(crate) async fn serve_until_stopped(
    serve: impl std::future::Future<Output = anyhow::Result<()>>,
    duration: Option<std::time::Duration>,
) -> anyhow::Result<()> {
    let mut interrupt = crate::interrupt::Interrupt::listen();
    tokio::select! {
        result = serve => result,
        () = run_for(duration) => Ok(()),
        () = interrupt.recv() => Ok(()),
    }
}

/// The console of a simulated device: each line of standard input (lower-cased words) an
/// operation on the device, run by its line's drive loop (between two exchanges, so an
/// operation never cuts a frame); `help` prints `help` instead. Whatever `operate`
/// returns is printed.
pub(crate) fn device_operations<E: 'static>(
    help: &'static str,
    operate: fn(&mut E, &[String]) -> String,
) -> tokio::sync::mpsc::UnboundedReceiver<iec60870::ft12::io::EndpointAction<E>> {
    let (operations, inbox) = tokio::sync::mpsc::unbounded_channel();
    let mut console = stdin_lines();
    tokio::spawn(async move {
        while let Some(line) = console.recv().await {
            let words: Vec<String> = line.split_whitespace().map(str::to_lowercase).collect();
            if words.is_empty() {
                continue;
            }
            if words.first().map(String::as_str) == Some("help") {
                println!("{help}");
                continue;
            }
            let operation: iec60870::ft12::io::EndpointAction<E> =
                Box::new(move |device: &mut E| println!("{}", operate(device, &words)));
            if operations.send(operation).is_err() {
                break;
            }
        }
    });
    inbox
}
