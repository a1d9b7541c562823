//! Ctrl-C (SIGINT) and SIGTERM for the commands that run until stopped.
//!
//! `tokio::signal::ctrl_c()` starts listening only when first polled, and each call is a
//! new listener: a Ctrl-C while a station was still starting, or between two turns of a
//! client's loop, was lost or killed the process without flushing anything. An
//! [`Interrupt`] listens from the moment it is made and keeps every signal until awaited.
//!
//! SIGTERM is what systemd, container runtimes and `kill` send: it stops the command as
//! Ctrl-C does (outputs driven safe, stores flushed, exit 0), not by the default action
//! that ended the process at once with status 143.

/// A listener for Ctrl-C and SIGTERM, registered when made.
pub(crate) struct Interrupt {
    #[cfg(unix)]
    interrupt: Option<tokio::signal::unix::Signal>,
    #[cfg(unix)]
    terminate: Option<tokio::signal::unix::Signal>,
    #[cfg(windows)]
    interrupt: Option<tokio::signal::windows::CtrlC>,
}

/// Registers one signal's listener; on failure the signal keeps its default action (it
/// ends the process), which is said once.
fn listener<S>(name: &str, signal: std::io::Result<S>) -> Option<S> {
    match signal {
        Ok(signal) => Some(signal),
        Err(error) => {
            eprintln!("warning: cannot listen for {name}: {error}");
            None
        }
    }
}

impl Interrupt {
    /// Starts listening; call it inside the tokio runtime, before the long work starts.
    pub(crate) fn listen() -> Interrupt {
        #[cfg(unix)]
        {
            use tokio::signal::unix::{signal, SignalKind};
            Interrupt {
                interrupt: listener("Ctrl-C", signal(SignalKind::interrupt())),
                terminate: listener("SIGTERM", signal(SignalKind::terminate())),
            }
        }
        #[cfg(windows)]
        {
            Interrupt {
                interrupt: listener("Ctrl-C", tokio::signal::windows::ctrl_c()),
            }
        }
    }

    /// Waits for a Ctrl-C or SIGTERM (one received since the last call counts).
    pub(crate) async fn recv(&mut self) {
        #[cfg(unix)]
        {
            tokio::select! {
                () = wait(self.interrupt.as_mut()) => {}
                () = wait(self.terminate.as_mut()) => {}
            }
        }
        #[cfg(windows)]
        {
            match &mut self.interrupt {
                Some(signal) => {
                    if signal.recv().await.is_none() {
                        std::future::pending::<()>().await;
                    }
                }
                None => std::future::pending::<()>().await,
            }
        }
    }
}

/// Waits for one delivery of a unix signal; forever when there is no listener or the
/// listener closed.
#[cfg(unix)]
async fn wait(signal: Option<&mut tokio::signal::unix::Signal>) {
    match signal {
        Some(signal) => {
            if signal.recv().await.is_none() {
                std::future::pending::<()>().await;
            }
        }
        None => std::future::pending::<()>().await,
    }
}
