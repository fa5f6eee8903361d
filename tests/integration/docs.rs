//! The reference made from the clap definitions: `docs/cli.md` equal to the help it is
//! generated from, `bsa completions` and `bsa man`, `bsa new --help` naming every
//! object form of the README, and `docs/solver.md` naming tests that exist.

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

/// Every test that `docs/solver.md`'s table names (its last column) is a test of the
/// crate: a `#[test]` function of that name under `tests/` or `src/`.
#[test]
fn docs_solver_md_names_tests_that_exist() {
    let page = std::fs::read_to_string(root().join("docs/solver.md")).unwrap();
    let mut sources = String::new();
    let mut dirs = vec![root().join("tests"), root().join("src")];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                sources.push_str(&std::fs::read_to_string(&path).unwrap());
            }
        }
    }
    // The rows of the table whose last column is "the test that shows it".
    let rows = page
        .lines()
        .skip_while(|l| !l.ends_with("| the test that shows it |"))
        .take_while(|l| l.starts_with('|'))
        .skip(2);
    let named: Vec<&str> = rows
        .filter_map(|row| row.trim_end_matches(" |").rsplit(" | ").next())
        .flat_map(|cell| cell.split('`').skip(1).step_by(2))
        .filter(|name| {
            name.chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
        })
        .collect();
    assert!(named.len() >= 10, "{named:?}");
    for name in named {
        assert!(
            sources.contains(&format!("#[test]\nfn {name}()"))
                || sources.contains(&format!("#[test]\n    fn {name}()")),
            "docs/solver.md names the test {name}, which no #[test] function is"
        );
    }
}
