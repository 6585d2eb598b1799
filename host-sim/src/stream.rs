//! Placeholder: the firmware engineer owns and replaces this file.

#[derive(clap::Args, Debug)]
pub struct StreamArgs {}

pub fn run(_: &StreamArgs) -> anyhow::Result<()> {
    anyhow::bail!("stream: not built yet")
}
