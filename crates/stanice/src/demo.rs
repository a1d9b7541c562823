//! `stanice demo`: runs the Vsetín railway station (`examples/vsetin`) with its embedded
//! defaults: every controller in this process, the plant simulation, SQLite events in the
//! project folder, the top controller serving the dispatch systems on 127.0.0.1:2404.
//!
//! The links between the controllers use TLS with mutual authentication (IEC 62351-3),
//! as links between processes and hosts should: on its first run the demo makes a
//! throwaway certificate authority and a certificate for each controller in the project's
//! `tls/` folder (reused by later runs, so that `--node` processes trust each other). The
//! top controller's own server stays plain IEC 104 for the dispatch tools and the HMI.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use clap::Args;
use iec60870::cs104::tls::self_signed::{write, Authority, Usage};
use iec60870::cs104::tls::TlsFiles;
use station::config::{LinkTarget, Project};

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
    run_project(&project_folder(), None, args.options, true).await
}

/// Puts every link between the project's controllers on TLS with mutual authentication,
/// with the certificates of the project's `tls/` folder (made on the first run).
pub(crate) fn secure_links(mut project: Project) -> anyhow::Result<Project> {
    let lower: BTreeSet<String> = project
        .nodes
        .iter()
        .flat_map(|node| &node.links)
        .filter_map(|link| match &link.target {
            LinkTarget::Node(name) => Some(name.clone()),
            LinkTarget::Address(_) => None,
        })
        .collect();
    let ends: BTreeSet<String> = project
        .nodes
        .iter()
        .filter(|node| lower.contains(&node.name) || !node.links.is_empty())
        .map(|node| node.name.clone())
        .collect();
    let folder = project.folder.join("tls");
    let names = [project.station.bind.to_string(), "localhost".to_owned()];
    let files = certificates(&folder, &ends, &names)
        .with_context(|| format!("the demo's certificates in {}", folder.display()))?;
    for node in &mut project.nodes {
        let Some(own) = files
            .iter()
            .find(|(name, _)| name == &node.name)
            .map(|(_, f)| f)
        else {
            continue;
        };
        if lower.contains(&node.name) {
            if let Some(server) = &mut node.server {
                server.tls = Some(own.clone());
            }
        }
        for link in &mut node.links {
            if matches!(&link.target, LinkTarget::Node(target) if lower.contains(target)) {
                link.tls = Some(own.clone());
            }
        }
    }
    Ok(project)
}

/// Each node's certificate files in `folder`: reused when every one is there, else all
/// made anew under a new authority.
fn certificates(
    folder: &Path,
    nodes: &BTreeSet<String>,
    names: &[String],
) -> anyhow::Result<Vec<(String, TlsFiles)>> {
    let stem = |node: &str| {
        node.chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() {
                    c.to_ascii_lowercase()
                } else {
                    '-'
                }
            })
            .collect::<String>()
    };
    let existing: Vec<(String, TlsFiles)> = nodes
        .iter()
        .map(|node| {
            let stem = stem(node);
            let files = TlsFiles {
                certificate: folder.join(format!("{stem}.pem")),
                private_key: folder.join(format!("{stem}.key")),
                trust_anchors: folder.join(format!("{stem}-ca.pem")),
            };
            (node.clone(), files)
        })
        .collect();
    let complete = || {
        existing.iter().all(|(_, files)| {
            files.certificate.is_file()
                && files.private_key.is_file()
                && files.trust_anchors.is_file()
        })
    };
    if complete() {
        return Ok(existing);
    }
    // Made in a folder of this process's own and moved into place in one step: two demos
    // starting at once (tests do) must not mix the certificates of two authorities.
    let parent = folder.parent().unwrap_or(Path::new("."));
    let scratch = parent.join(format!(".tls-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&scratch);
    std::fs::create_dir_all(&scratch)?;
    let authority = Authority::new("Stanice demo CA (throwaway)")?;
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    for node in nodes {
        let pem = authority.issue(&names, Usage::ServerAndClient)?;
        write(&pem, &scratch, &stem(node))?;
    }
    // An incomplete folder (an older project's, or a run cut short) is replaced; a
    // complete one another demo put there meanwhile is kept.
    if folder.exists() && !complete() {
        let _ = std::fs::remove_dir_all(folder);
    }
    match std::fs::rename(&scratch, folder) {
        Ok(()) => println!(
            "made throwaway TLS certificates for the links between the controllers in {}",
            folder.display()
        ),
        // Another demo was quicker: take its certificates.
        Err(_) => {
            let _ = std::fs::remove_dir_all(&scratch);
        }
    }
    anyhow::ensure!(complete(), "the certificates could not be put in place");
    Ok(existing)
}
