//! `plamo view DIR...`: the replay viewer, a self-contained HTML page (three.js,
//! the run's glTF and overlay data inlined) for one or more recorded runs.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;

/// Arguments of `plamo view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// Recording directories (`plamo run --out DIR`); several are shown side by side.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Write the page here (default: `view.html` in the first directory).
    #[arg(long)]
    write_html: Option<PathBuf>,
    /// Do not try to open the page in a browser.
    #[arg(long)]
    no_open: bool,
}

/// Run `plamo view`.
pub fn run(args: ViewArgs) -> anyhow::Result<ExitCode> {
    let out = args
        .write_html
        .clone()
        .unwrap_or_else(|| args.dirs[0].join("view.html"));
    let dirs: Vec<&std::path::Path> = args.dirs.iter().map(PathBuf::as_path).collect();
    plamo::export::write_viewer(&dirs, &out)?;
    say!("wrote {}", out.display());
    // Only an explicit page request or a missing display keeps the browser closed.
    let display =
        std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some();
    if args.write_html.is_none() && !args.no_open && display {
        let _ = std::process::Command::new("xdg-open")
            .arg(&out)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn();
    }
    Ok(ExitCode::SUCCESS)
}
