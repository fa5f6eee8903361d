//! Two rules of the prose of README.md and docs/*.md: no phrase that dates the text to a
//! round of work or a session ("this round", "the round before", "this session", "now"
//! ...: a figure names its commit instead), and no sentence longer than 60 words.
//!
//! Sentences are split on `. `, `? ` and `! `, within a paragraph (its lines joined),
//! a list item or a heading; every cell of a table row counts on its own. Fenced code
//! blocks are left out (commands and the help text of docs/cli.md), and so are HTML
//! lines (`<img ...>`) and the `<!-- ... -->` markers of the generated tables.

use crate::util::root;

/// The most words a sentence may have.
const MAX_WORDS: usize = 60;

/// Phrases that date a text to when it was written (lower case).
const DATED: [&str; 24] = [
    "this round",
    "the round before",
    "a round earlier",
    "a round before",
    "a later round",
    "later rounds",
    "an earlier round",
    "earlier rounds",
    "previous round",
    "last round",
    "next round",
    "latest round",
    "rounds back",
    "rounds ago",
    "this session",
    "a later session",
    "earlier session",
    "previous session",
    "last session",
    "this sitting",
    "today's",
    "these days",
    "so far this",
    "at present",
];

/// README.md and docs/*.md.
fn pages() -> Vec<std::path::PathBuf> {
    let mut out = vec![root().join("README.md")];
    let mut docs: Vec<_> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    out.extend(docs);
    out
}

/// The text units of a page, each with its first line: paragraphs, list items, headings
/// and table cells, code blocks and HTML lines left out.
fn units(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut current: Option<(usize, String)> = None;
    let mut code = false;
    let flush = |current: &mut Option<(usize, String)>, out: &mut Vec<(usize, String)>| {
        if let Some(u) = current.take() {
            out.push(u);
        }
    };
    for (k, line) in text.lines().enumerate() {
        let n = k + 1;
        let t = line.trim();
        if t.starts_with("```") {
            code = !code;
            flush(&mut current, &mut out);
            continue;
        }
        if code || t.starts_with('<') {
            flush(&mut current, &mut out);
            continue;
        }
        if t.starts_with('|') {
            flush(&mut current, &mut out);
            for cell in t.trim_matches('|').split('|') {
                out.push((n, cell.trim().to_string()));
            }
            continue;
        }
        let item = t.starts_with("- ")
            || t.starts_with("* ")
            || t.starts_with('#')
            || t.split_once(". ")
                .is_some_and(|(a, _)| !a.is_empty() && a.chars().all(|c| c.is_ascii_digit()));
        if t.is_empty() || item {
            flush(&mut current, &mut out);
        }
        if t.is_empty() {
            continue;
        }
        match &mut current {
            Some((_, s)) => {
                s.push(' ');
                s.push_str(t);
            }
            None => current = Some((n, t.to_string())),
        }
    }
    flush(&mut current, &mut out);
    out
}

/// The sentences of a unit of text.
fn sentences(unit: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = unit;
    while let Some(at) = [". ", "? ", "! "]
        .iter()
        .filter_map(|sep| rest.find(sep))
        .min()
    {
        out.push(rest[..=at].to_string());
        rest = &rest[at + 2..];
    }
    out.push(rest.to_string());
    out
}

/// Whether `text` holds the word "now" (as "is now", "now takes" ...).
fn says_now(text: &str) -> bool {
    text.split(|c: char| !c.is_alphanumeric() && c != '\'')
        .any(|w| w.eq_ignore_ascii_case("now"))
}

#[test]
fn readme_and_docs_name_no_round_or_session_and_no_sentence_runs_past_60_words() {
    let mut faults = Vec::new();
    for path in pages() {
        let text = std::fs::read_to_string(&path).unwrap();
        let name = path.strip_prefix(root()).unwrap().display().to_string();
        for (line, unit) in units(&text) {
            let lower = unit.to_lowercase();
            for phrase in DATED {
                if lower.contains(phrase) {
                    faults.push(format!("{name}:{line}: dated phrase {phrase:?}"));
                }
            }
            if says_now(&unit) {
                faults.push(format!("{name}:{line}: \"now\" dates the text"));
            }
            for s in sentences(&unit) {
                let words = s.split_whitespace().count();
                if words > MAX_WORDS {
                    let start: String = s.chars().take(80).collect();
                    faults.push(format!("{name}:{line}: {words} words: {start}..."));
                }
            }
        }
    }
    assert!(
        faults.is_empty(),
        "{} faults:\n{}",
        faults.len(),
        faults.join("\n")
    );
}

#[test]
fn the_sentence_splitter_counts_cells_and_skips_code() {
    let text = "A short one. Another?\n\n| a b c | d e |\n|---|---|\n\n```sh\nnow now\n```\n- an item\n  running on\n";
    let u = units(text);
    let texts: Vec<&str> = u.iter().map(|(_, s)| s.as_str()).collect();
    assert_eq!(
        texts,
        [
            "A short one. Another?",
            "a b c",
            "d e",
            "---",
            "---",
            "- an item running on"
        ]
    );
    assert_eq!(sentences("A short one. Another? Yes! Done").len(), 4);
    assert!(says_now("It is now faster") && !says_now("a known nowhere"));
}

/// The front page and the results stay short: README.md at most 200 lines,
/// docs/results.md at most 500.
#[test]
fn readme_and_results_stay_short() {
    for (page, most) in [("README.md", 200), ("docs/results.md", 500)] {
        let n = std::fs::read_to_string(root().join(page))
            .unwrap()
            .lines()
            .count();
        assert!(n <= most, "{page} has {n} lines, more than {most}");
    }
}
