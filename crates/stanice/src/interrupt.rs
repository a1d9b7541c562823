//! Ctrl-C (SIGINT) for the commands that run until stopped.
//!
//! `tokio::signal::ctrl_c()` starts listening only when first polled, and each call is a
//! new listener: a Ctrl-C while a station was still starting, or between two turns of a
//! client's loop, was lost or killed the process without flushing anything. An
//! [`Interrupt`] listens from the moment it is made and keeps every Ctrl-C until awaited.

/// A Ctrl-C listener, registered when made.
pub(crate) struct Interrupt {
    #[cfg(unix)]
    signal: Option<tokio::signal::unix::Signal>,
    #[cfg(windows)]
    signal: Option<tokio::signal::windows::CtrlC>,
}

impl Interrupt {
    /// Starts listening; call it inside the tokio runtime, before the long work starts.
    pub(crate) fn listen() -> Interrupt {
        #[cfg(unix)]
        let signal = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::interrupt());
        #[cfg(windows)]
        let signal = tokio::signal::windows::ctrl_c();
        let signal = match signal {
            Ok(signal) => Some(signal),
            Err(error) => {
                // Ctrl-C then keeps its default action: it ends the process.
                eprintln!("warning: cannot listen for Ctrl-C: {error}");
                None
            }
        };
        Interrupt { signal }
    }

    /// Waits for a Ctrl-C (one received since the last call counts).
    pub(crate) async fn recv(&mut self) {
        match &mut self.signal {
            Some(signal) => {
                if signal.recv().await.is_none() {
                    std::future::pending::<()>().await;
                }
            }
            None => std::future::pending::<()>().await,
        }
    }
}
