//! `stanice demo`: runs the Vsetín railway station (`examples/vsetin`) with its embedded
//! defaults: every controller in this process, the plant simulation, SQLite events in the
//! project folder, the top controller serving the dispatch systems on 127.0.0.1:2404.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;

use crate::run::{run_project, RunOptions};

/// Arguments of `stanice demo`.
#[derive(Args, Debug)]
pub(crate) struct DemoArgs {
    #[command(flatten)]
    options: RunOptions,
}

/// The example project: next to the binary's sources in a checkout, or `examples/vsetin`
/// under the current directory.
fn project_folder() -> PathBuf {
    let in_checkout = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/vsetin");
    if in_checkout.join("station.toml").is_file() {
        return in_checkout.canonicalize().unwrap_or(in_checkout);
    }
    PathBuf::from("examples/vsetin")
}

pub(crate) async fn run(args: DemoArgs) -> anyhow::Result<ExitCode> {
    run_project(&project_folder(), args.options, true).await
}
