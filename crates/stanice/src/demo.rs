//! `stanice demo`: the railway-station demo.
//!
//! Today it runs the first piece of the Vsetín station: the RH2 power board's data points
//! as the RH1.1 concentrator serves them over IEC 104 (IOA 281-298, commands 2021/2022),
//! with simulated changes. The whole controller hierarchy joins it as the station runtime
//! grows.

use std::net::{Ipv4Addr, SocketAddr};
use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use iec60870::asdu::CommonAddress;
use iec60870::cs104::server::ServerConfig;

use crate::iec104;

/// The RH2 point list shipped with the Vsetín example.
const RH2_POINTS: &str = include_str!("../../../examples/vsetin/rh2-iec104-points.csv");

/// Arguments of `stanice demo`.
#[derive(Args, Debug)]
pub(crate) struct DemoArgs {
    /// First TCP port; the dispatch-facing IEC 104 server listens on it.
    #[arg(long, default_value_t = 2404)]
    port_base: u16,
    /// Stop after this many seconds (runs until Ctrl-C otherwise).
    #[arg(long)]
    duration: Option<f64>,
}

pub(crate) async fn run(args: DemoArgs) -> anyhow::Result<ExitCode> {
    let points = iec104::points_file::parse(RH2_POINTS)
        .map_err(|error| anyhow::anyhow!("examples/vsetin/rh2-iec104-points.csv:{error}"))?;
    let rows = points.monitor.clone();
    let listen = SocketAddr::from((Ipv4Addr::LOCALHOST, args.port_base));
    let server =
        iec104::serve_points(ServerConfig::new(listen, CommonAddress::new(1)), points).await?;
    tokio::spawn(iec104::simulate::run(
        server.clone(),
        rows,
        Duration::from_secs(2),
    ));
    println!("Stanice demo: Vsetín railway station, board RH2 (via concentrator RH1.1)");
    println!(
        "  IEC 104 outstation on {} (common address 1)",
        server.local_addr()
    );
    println!("  18 single points IOA 281-298 change every few seconds; commands at IOA 2021/2022.");
    println!("Look at it from another terminal:");
    println!(
        "  cargo run --release -- iec104 client {} --gi",
        server.local_addr()
    );
    println!(
        "  cargo run --release -- iec104 command {} --ca 1 --ioa 2022 --type C_SC_NA_1 --value 1",
        server.local_addr()
    );
    println!("Press Ctrl-C to stop.");
    match args.duration {
        Some(seconds) => tokio::time::sleep(Duration::from_secs_f64(seconds.clamp(0.0, 1e9))).await,
        None => {
            let _ = tokio::signal::ctrl_c().await;
        }
    }
    server.shutdown();
    Ok(ExitCode::SUCCESS)
}
