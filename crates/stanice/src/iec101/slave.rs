//! `stanice iec101 slave`: an outstation on a serial line serving a CSV point list.

use std::ops::ControlFlow;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use clap::Args;
use iec60870::asdu::CommonAddress;
use iec60870::ft12::io::drive;
use iec60870::ft12::{Balanced, BalancedConfig, Secondary, SecondaryConfig, SecondaryStation};
use iec60870::iec101::{BalancedSlave, Slave};
use iec60870::outstation::{Outstation, OutstationConfig, Peer, StationHandler};
use tokio::sync::mpsc;

use super::FieldSizes;
use crate::iec104::points_file;
use crate::iec104::server::CommandLogger;
use crate::serial_line::{report_end, LineArgs, ServedLines};

/// Arguments of `stanice iec101 slave`.
#[derive(Args, Debug)]
pub(crate) struct SlaveArgs {
    #[command(flatten)]
    line: LineArgs,
    /// This outstation's link address.
    #[arg(long, default_value_t = 1)]
    address: u16,
    /// The station's common address.
    #[arg(long, default_value_t = 1)]
    ca: u16,
    /// CSV point list (header `ioa,type,value`), as for `stanice iec104 server`.
    #[arg(long)]
    points: PathBuf,
    /// Change values over time and send them spontaneously.
    #[arg(long)]
    simulate: bool,
    /// The time between simulated changes (`1s`, `100ms`; a plain number is seconds).
    #[arg(long, value_name = "TIME", default_value = "1s", value_parser = crate::duration_arg::seconds)]
    simulate_interval: Duration,
    /// Stop after this long (`30s`, `10m`; a plain number is seconds); runs until Ctrl-C
    /// or SIGTERM otherwise.
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    duration: Option<std::time::Duration>,
    /// Answer "ACK" and "no data" with the single character E5 where allowed.
    #[arg(long)]
    single_char: bool,
    /// The zone of time tags: `UTC` or a zone name such as `Europe/Prague`.
    #[arg(long, default_value = "UTC")]
    time_zone: iec60870::time::TimeZonePolicy,
    #[command(flatten)]
    sizes: FieldSizes,
}

pub(crate) async fn run(args: SlaveArgs) -> anyhow::Result<ExitCode> {
    let settings = args.line.settings()?;
    let points = points_file::load(&args.points)?;
    let mut config = OutstationConfig::new(CommonAddress::new(args.ca), args.sizes.params()?);
    config.time_zone = args.time_zone;
    let handler = Arc::new(CommandLogger::new(points.command_names.clone()));
    let summary = format!(
        "{} monitor points, {} command points",
        points.monitor.len(),
        points.commands.len()
    );
    let monitor_rows = points.monitor.clone();
    let outstation = Arc::new(Outstation::new(
        config,
        points.image,
        Arc::clone(&handler) as Arc<dyn StationHandler>,
    )?);
    handler.serve(Arc::clone(&outstation));
    if args.simulate {
        let interval = args.simulate_interval.max(Duration::from_millis(1));
        tokio::spawn(crate::iec104::simulate::run(
            Arc::clone(&outstation),
            monitor_rows,
            interval,
        ));
    }
    let secondary = SecondaryConfig {
        address_size: args.sizes.address_size(),
        address: args.address,
        single_character: args.single_char,
        class1_on_class2_request: false,
    };
    let serve = async {
        let mut lines = ServedLines::new(&args.line).await?;
        let mut id = 0;
        while let Some(line) = lines.next().await? {
            id += 1;
            println!(
                "IEC 101 outstation at link address {} (common address {}) on {}, {summary}",
                args.address, args.ca, line.peer
            );
            let peer = Peer::Serial {
                port: line.peer.as_str().into(),
                link_address: args.address,
            };
            let now = tokio::time::Instant::now().into_std();
            let end = if args.sizes.balanced {
                let link = Balanced::new(
                    BalancedConfig {
                        address_size: args.sizes.address_size(),
                        line: settings,
                        ..BalancedConfig::new(args.address, false)
                    },
                    now,
                );
                let Some(mut slave) = BalancedSlave::new(&outstation, id, peer, link) else {
                    anyhow::bail!("the outstation takes no link");
                };
                let (_keep, mut actions) = mpsc::unbounded_channel();
                let end = drive(line.stream, &mut slave, &mut actions, |_| {
                    ControlFlow::Continue(())
                })
                .await;
                slave.close();
                end
            } else {
                let Some(slave) = Slave::new(&outstation, id, peer, now) else {
                    anyhow::bail!("the outstation takes no link");
                };
                let mut station = SecondaryStation::new(settings, Secondary::new(secondary), slave);
                let (_keep, mut actions) = mpsc::unbounded_channel();
                let end = drive(line.stream, &mut station, &mut actions, |_| {
                    ControlFlow::Continue(())
                })
                .await;
                station.into_app().close();
                end
            };
            report_end(&line.peer, end);
        }
        Ok::<(), anyhow::Error>(())
    };
    crate::console::serve_until_stopped(serve, args.duration).await?;
    Ok(ExitCode::SUCCESS)
}
