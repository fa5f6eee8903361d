//! The reference of the command line, made from the clap definitions so that it cannot
//! drift from `--help`: [`markdown`] (`docs/cli.md`, kept equal to it by a test),
//! `bsa completions` (clap_complete) and `bsa man` (clap_mangen).

use std::io::Write;

use anyhow::{bail, Context, Result};
use clap::{CommandFactory, ValueEnum};

use super::Cli;

/// The command that rewrites `docs/cli.md`, named at its top.
pub const REGENERATE: &str = "BSA_REGENERATE=1 cargo test --test integration docs::";

/// The shells `bsa completions` writes a script for.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub(super) enum Shell {
    Bash,
    Zsh,
    Fish,
}

/// The command line's definitions, built: every subcommand knows its full name
/// (`bsa solve`) for its usage line.
fn command() -> clap::Command {
    let mut cmd = Cli::command();
    cmd.build();
    cmd
}

/// The subcommands a user runs, in the order of `bsa --help` (clap's own `help` left out).
fn subcommands(cmd: &clap::Command) -> impl Iterator<Item = &clap::Command> {
    cmd.get_subcommands()
        .filter(|c| c.get_name() != "help" && !c.is_hide_set())
}

/// `docs/cli.md`: the long help (`--help`) of `bsa` and of every subcommand, as markdown.
pub fn markdown() -> String {
    let cmd = command();
    let mut out = String::new();
    out.push_str("# Command line\n\n");
    out.push_str(&format!(
        "This page is `bsa --help` and `bsa <command> --help`, generated from the clap \
         definitions in `src/cli/mod.rs` by `bsa::cli::markdown`; do not edit it by hand. \
         After changing the help, regenerate it with\n\n```sh\n{REGENERATE}\n```\n\n\
         (without `BSA_REGENERATE=1` that test fails while this page differs from the \
         help). `bsa completions bash|zsh|fish` prints a shell's completion script and \
         `bsa man [COMMAND]` the manual page, from the same definitions.\n\n"
    ));
    for sub in subcommands(&cmd) {
        let about = sub.get_about().map(|a| a.to_string()).unwrap_or_default();
        out.push_str(&format!(
            "- [`bsa {name}`](#bsa-{name}): {about}\n",
            name = sub.get_name()
        ));
    }
    out.push('\n');
    section(&mut out, &[]);
    for sub in subcommands(&cmd) {
        section(&mut out, &[sub.get_name()]);
    }
    out
}

/// The help `bsa <command> --help` prints (the long help where an option has one, else
/// the short), under a heading, trailing spaces trimmed.
fn section(out: &mut String, command: &[&str]) {
    let args = ["bsa"].iter().chain(command).chain(&["--help"]);
    let help = match Cli::command().try_get_matches_from(args) {
        Err(e) if e.kind() == clap::error::ErrorKind::DisplayHelp => e.render().to_string(),
        _ => unreachable!("--help prints the help"),
    };
    let title = ["bsa"]
        .iter()
        .chain(command)
        .copied()
        .collect::<Vec<_>>()
        .join(" ");
    let help: Vec<&str> = help.lines().map(str::trim_end).collect();
    out.push_str(&format!(
        "## {title}\n\n```text\n{}\n```\n\n",
        help.join("\n").trim_end()
    ));
}

/// `bsa completions SHELL`: the script on standard output.
pub(super) fn completions(shell: Shell) -> Result<()> {
    let mut cmd = Cli::command();
    let mut out = std::io::stdout().lock();
    match shell {
        Shell::Bash => {
            clap_complete::generate(clap_complete::Shell::Bash, &mut cmd, "bsa", &mut out)
        }
        Shell::Zsh => clap_complete::generate(clap_complete::Shell::Zsh, &mut cmd, "bsa", &mut out),
        Shell::Fish => {
            clap_complete::generate(clap_complete::Shell::Fish, &mut cmd, "bsa", &mut out)
        }
    }
    out.flush().context("cannot write the completion script")
}

/// `bsa man [SUBCOMMAND]`: the manual page, roff, on standard output.
pub(super) fn man(subcommand: Option<&str>) -> Result<()> {
    let cmd = command();
    let page = match subcommand {
        None => cmd,
        Some(name) => match subcommands(&cmd).find(|c| c.get_name() == name) {
            Some(sub) => sub.clone().version(env!("CARGO_PKG_VERSION")),
            None => {
                let names: Vec<&str> = subcommands(&cmd).map(|c| c.get_name()).collect();
                bail!("no subcommand `{name}` (one of {})", names.join(", "))
            }
        },
    };
    let mut roff = Vec::new();
    clap_mangen::Man::new(page)
        .render(&mut roff)
        .context("cannot write the manual page")?;
    let mut out = std::io::stdout().lock();
    out.write_all(&roff)
        .and_then(|()| out.flush())
        .context("cannot write the manual page")
}
