//! The reference made from the clap definitions: `docs/cli.md` equal to the help it is
//! generated from, `bsa completions` and `bsa man`, and `bsa new --help` naming every
//! object form of the README.

use std::process::Command;

use crate::util::{bsa, root};

/// The help's subcommands, as `bsa --help` lists them.
const SUBCOMMANDS: [&str; 13] = [
    "check",
    "solve",
    "export",
    "validate",
    "blend",
    "video",
    "budget",
    "eval",
    "render",
    "plant",
    "new",
    "completions",
    "man",
];

/// `docs/cli.md` is `bsa::cli::markdown()`; with `BSA_REGENERATE=1` the test writes it
/// instead (the command named at the top of the page).
#[test]
fn docs_cli_md_is_the_help_of_every_command() {
    let path = root().join("docs/cli.md");
    let made = bsa::cli::markdown();
    crate::util::generated(
        &path,
        &made,
        "docs/cli.md differs from the help",
        "cargo test --test integration docs::",
    );
    // Every subcommand has its section, and each section is what `--help` prints.
    for sub in SUBCOMMANDS {
        assert!(made.contains(&format!("\n## bsa {sub}\n")), "{sub}");
    }
    let (ok, help, err) = bsa(&["budget", "--help"]);
    assert!(ok, "{err}");
    let trimmed: Vec<&str> = help.lines().map(str::trim_end).collect();
    assert!(
        made.contains(&format!(
            "## bsa budget\n\n```text\n{}\n```",
            trimmed.join("\n").trim_end()
        )),
        "the budget section is not `bsa budget --help`"
    );
}

#[test]
fn bash_completions_name_every_subcommand_and_parse() {
    let (ok, script, err) = bsa(&["completions", "bash"]);
    assert!(ok, "{err}");
    assert!(
        script.contains("complete") && script.contains("bsa"),
        "{script}"
    );
    for sub in SUBCOMMANDS {
        assert!(
            script.contains(sub),
            "{sub} missing from the bash completions"
        );
    }
    assert!(
        script.contains("--free-positions"),
        "solve's options missing"
    );
    // `bash -n` reads the script without running it.
    match Command::new("bash")
        .arg("-n")
        .arg("-c")
        .arg(&script)
        .output()
    {
        Ok(o) => assert!(
            o.status.success(),
            "bash -n refuses the script: {}",
            String::from_utf8_lossy(&o.stderr)
        ),
        Err(e) => eprintln!("note: no bash to check the script with ({e})"),
    }
    for shell in ["zsh", "fish"] {
        let (ok, script, err) = bsa(&["completions", shell]);
        assert!(
            ok && script.contains("solve") && script.contains("budget"),
            "{shell}: {err}"
        );
    }
    let (ok, _, err) = bsa(&["completions", "tcsh"]);
    assert!(!ok && err.contains("tcsh"), "{err}");
}

#[test]
fn the_man_page_is_roff_of_the_help() {
    let (ok, page, err) = bsa(&["man"]);
    assert!(ok, "{err}");
    assert!(
        page.starts_with(".ie") || page.contains(".TH bsa"),
        "{page}"
    );
    assert!(
        page.contains(".TH bsa") && page.contains(".SH NAME"),
        "{page}"
    );
    for sub in SUBCOMMANDS {
        assert!(page.contains(sub), "{sub} missing from the man page");
    }
    let (ok, page, err) = bsa(&["man", "solve"]);
    assert!(ok, "{err}");
    assert!(
        page.contains(".TH") && page.contains("\\-\\-free\\-positions"),
        "{page}"
    );
    let (ok, _, err) = bsa(&["man", "fly"]);
    assert!(
        !ok && err.contains("no subcommand `fly`") && err.contains("budget"),
        "{err}"
    );
}

/// The forms the README's "Your own picture" gives for `--objects`, each named by `bsa
/// new --help`.
#[test]
fn new_help_names_every_object_form() {
    let (ok, help, err) = bsa(&["new", "--help"]);
    assert!(ok, "{err}");
    for form in [
        "sphere:R",
        "box:XxYxZ",
        "mesh:FILE.obj[@SCALE]",
        "chess:PIECE",
        "`chess`",
        "*N",
        "/DENSITY",
        "auto:sphere",
        "auto:sphere:R",
        "auto:box:XxYxZ",
        "auto:mesh:FILE.obj[@SCALE]",
        "auto:chess",
        "FILE.json",
        "king, queen, rook, bishop, knight or pawn",
    ] {
        assert!(
            help.contains(form),
            "`bsa new --help` does not name {form}:\n{help}"
        );
    }
}
