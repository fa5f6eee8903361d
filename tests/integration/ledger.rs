//! The results ledger: every table of `docs/results.md` between `<!-- table:NAME -->`
//! and `<!-- end -->` is made from the CSV files of `results/`, which the suites append
//! rows to (`scripts/ledger.sh`). `BSA_REGENERATE=1 cargo test --test integration
//! ledger::` writes the tables; without it the test fails when they differ.
//!
//! A table the ledger does not derive (a measurement recorded once, with its commit in
//! a column or in the text around it) is `results/tables/NAME.csv`: its first row the
//! column headers, each further row a row of the table, every cell as the page shows
//! it. No table of the page lies outside the markers.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::util::root;

/// The ledger's columns, in order.
const COLUMNS: [&str; 11] = [
    "commit",
    "date",
    "machine",
    "suite",
    "set_or_seed",
    "item",
    "route",
    "iou",
    "contacts",
    "samples",
    "seconds",
];

/// The tables `docs/results.md` must hold.
const TABLES: [&str; 5] = [
    "examples",
    "speed",
    "planted",
    "new-suite",
    "new-suite-latest",
];

/// The planted draws the page shows, the last in the ledger.
const LAST_DRAWS: usize = 4;
/// The runs of the `bsa new` suite the page shows, the last in the ledger.
const LAST_RUNS: usize = 6;

/// One row of a ledger file.
#[derive(Clone, Debug)]
struct Row {
    commit: String,
    date: String,
    set_or_seed: String,
    item: String,
    route: String,
    iou: Option<f64>,
    contacts: Option<u64>,
    samples: Option<u64>,
    seconds: Option<f64>,
}

/// The rows of `results/<suite>.csv`, in file order.
fn ledger(suite: &str) -> Vec<Row> {
    let path = root().join(format!("results/{suite}.csv"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    assert_eq!(
        lines.next().map(|h| h.split(',').collect::<Vec<_>>()),
        Some(COLUMNS.to_vec()),
        "{}: the header is not the ledger's columns",
        path.display()
    );
    lines
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(k, l)| {
            let f: Vec<&str> = l.split(',').collect();
            let at = || format!("{} line {}", path.display(), k + 2);
            assert_eq!(f.len(), COLUMNS.len(), "{}: {l}", at());
            assert_eq!(f[3], suite, "{}: the suite is not the file's", at());
            let num = |s: &str| -> Option<f64> {
                (!s.is_empty()).then(|| s.parse().unwrap_or_else(|_| panic!("{}: {s}", at())))
            };
            let int = |s: &str| -> Option<u64> {
                (!s.is_empty()).then(|| s.parse().unwrap_or_else(|_| panic!("{}: {s}", at())))
            };
            Row {
                commit: f[0].into(),
                date: f[1].into(),
                set_or_seed: f[4].into(),
                item: f[5].into(),
                route: f[6].into(),
                iou: num(f[7]),
                contacts: int(f[8]),
                samples: int(f[9]),
                seconds: num(f[10]),
            }
        })
        .collect()
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    })
}

fn iou(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |x| format!("{x:.4}"))
}

fn secs(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |x| format!("{x:.2} s"))
}

/// Thousands separated by commas.
fn count(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (k, c) in s.chars().enumerate() {
        if k > 0 && (s.len() - k).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// The examples' names as the text gives them.
fn scene_name(item: &str) -> &str {
    match item {
        "mickey" => "Mickey",
        "fly" => "飞 \"to fly\"",
        "tbc" => "つづく TBC",
        "thinker" => "THE THINKER",
        other => other,
    }
}

/// The paper's Table 3 total running time, in seconds.
fn paper_seconds(item: &str) -> Option<(f64, &'static str)> {
    match item {
        "mickey" => Some((29.0 * 60.0 + 7.0, "29 min 07 s")),
        "fly" => Some((16.0 * 60.0 + 55.0, "16 min 55 s")),
        "tbc" => Some((44.0 * 60.0 + 57.0, "44 min 57 s")),
        "thinker" => Some((396.0 * 60.0 + 15.0, "396 min 15 s")),
        _ => None,
    }
}

/// The items of `rows` in order of first appearance.
fn items(rows: &[Row]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in rows {
        if !out.contains(&r.item) {
            out.push(r.item.clone());
        }
    }
    out
}

/// The examples at seeds 1 to 3: each scene's last commit with a row for seed 1.
fn table_examples() -> String {
    let rows = ledger("bench");
    let mut t = String::from(
        "| scene | IoU at t, seeds 1 / 2 / 3 | median | contact before t | commit |\n|---|---|---|---|---|\n",
    );
    for item in items(&rows) {
        let mine: Vec<&Row> = rows.iter().filter(|r| r.item == item).collect();
        let Some(last) = mine.iter().rev().find(|r| r.set_or_seed == "1") else {
            continue;
        };
        let of = |seed: &str| {
            mine.iter()
                .rev()
                .find(|r| r.commit == last.commit && r.set_or_seed == seed)
                .and_then(|r| r.iou)
        };
        let seeds: Vec<Option<f64>> = ["1", "2", "3"].iter().map(|s| of(s)).collect();
        let contacts: Vec<u64> = mine
            .iter()
            .filter(|r| r.commit == last.commit)
            .filter_map(|r| r.contacts)
            .collect();
        let contacts = if contacts.iter().all(|&c| c == 0) {
            format!("none ({} seeds)", contacts.len())
        } else {
            format!(
                "{} of {} seeds",
                contacts.iter().filter(|&&c| c > 0).count(),
                contacts.len()
            )
        };
        let _ = writeln!(
            t,
            "| {} | {} | {} | {} | {} |",
            scene_name(&item),
            seeds
                .iter()
                .map(|&v| iou(v))
                .collect::<Vec<_>>()
                .join(" / "),
            iou(median(seeds.iter().flatten().copied().collect())),
            contacts,
            last.commit
        );
    }
    t
}

/// Seed 1's samples and solver wall time against the paper's Table 3.
fn table_speed() -> String {
    let rows = ledger("bench");
    let mut t = String::from(
        "| seed 1 | IoU at t | samples | solver wall time | the paper's total running time | speed-up | commit, date |\n|---|---|---|---|---|---|---|\n",
    );
    for item in items(&rows) {
        let Some(r) = rows
            .iter()
            .rev()
            .find(|r| r.item == item && r.set_or_seed == "1" && r.seconds.is_some())
        else {
            continue;
        };
        let seconds = r.seconds.unwrap_or_default();
        let (paper, speedup) = match paper_seconds(&item) {
            Some((p, text)) => (
                text.to_string(),
                format!("{} x", count((p / seconds).round() as u64)),
            ),
            None => ("-".into(), "-".into()),
        };
        let _ = writeln!(
            t,
            "| {} | {} | {} | **{}** | {} | {} | {}, {} |",
            scene_name(&item),
            iou(r.iou),
            r.samples.map_or_else(|| "-".into(), count),
            secs(r.seconds),
            paper,
            speedup,
            r.commit,
            r.date
        );
    }
    t
}

/// The examples' designs by `bsa new`: each scene's last row.
fn table_make_examples() -> String {
    let rows = ledger("make-examples");
    let mut t = String::from(
        "| scene | start guess IoU | contact before t | `bsa new` wall time, trial solves included | commit, date |\n|---|---|---|---|---|\n",
    );
    for item in items(&rows) {
        let Some(r) = rows.iter().rev().find(|r| r.item == item) else {
            continue;
        };
        let contact = match r.contacts {
            Some(0) => "none".to_string(),
            Some(n) => n.to_string(),
            None => "-".to_string(),
        };
        let _ = writeln!(
            t,
            "| {} | {} | {contact} | {} | {}, {} |",
            scene_name(&item),
            iou(r.iou),
            secs(r.seconds),
            r.commit,
            r.date
        );
    }
    t
}

/// The last `n` runs of a suite in the ledger's order, each named by its commit, set or
/// seed, and route.
fn last_runs(rows: &[Row], n: usize) -> Vec<(String, String, String)> {
    let mut runs: Vec<(String, String, String)> = Vec::new();
    for r in rows {
        let key = (r.commit.clone(), r.set_or_seed.clone(), r.route.clone());
        if !runs.contains(&key) {
            runs.push(key);
        }
    }
    runs.split_off(runs.len().saturating_sub(n))
}

/// The last planted draws: per class the median and lowest IoU and the median wall time.
/// A draw's rows are one per problem (item `<class> <seed>`) or, where only the summary
/// was kept, `<class> median` and `<class> lowest`.
fn table_planted() -> String {
    let rows = ledger("planted");
    // The last draws only, so that the page stays short as the ledger grows.
    let draws = last_runs(&rows, LAST_DRAWS);
    let mut t = String::from(
        "| draw (first seed) | route | class | problems | median IoU | lowest IoU | contact before t | median wall time | commit |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for (commit, first, route) in draws {
        let mine: Vec<&Row> = rows
            .iter()
            .filter(|r| r.commit == commit && r.set_or_seed == first && r.route == route)
            .collect();
        let mut classes: Vec<String> = Vec::new();
        for r in &mine {
            let class = r.item.split(' ').next().unwrap_or_default().to_string();
            if !classes.contains(&class) {
                classes.push(class);
            }
        }
        for class in classes {
            let of = |suffix: &str| {
                mine.iter()
                    .find(|r| r.item == format!("{class} {suffix}"))
                    .copied()
            };
            let problems: Vec<&&Row> = mine
                .iter()
                .filter(|r| {
                    r.item
                        .strip_prefix(&format!("{class} "))
                        .is_some_and(|s| s.chars().all(|c| c.is_ascii_digit()))
                })
                .collect();
            let (n, med, low, wall, contacts) = if problems.is_empty() {
                let (m, l) = (of("median"), of("lowest"));
                let contacts: Vec<u64> =
                    [m, l].iter().flatten().filter_map(|r| r.contacts).collect();
                (
                    "-".to_string(),
                    m.and_then(|r| r.iou),
                    l.and_then(|r| r.iou),
                    m.and_then(|r| r.seconds),
                    contacts.iter().any(|&c| c > 0),
                )
            } else {
                let ious: Vec<f64> = problems.iter().filter_map(|r| r.iou).collect();
                (
                    problems.len().to_string(),
                    median(ious.clone()),
                    ious.iter().copied().reduce(f64::min),
                    median(problems.iter().filter_map(|r| r.seconds).collect()),
                    problems.iter().any(|r| r.contacts.unwrap_or(0) > 0),
                )
            };
            let _ = writeln!(
                t,
                "| {first} | {route} | {class} | {n} | {} | {} | {} | {} | {commit} |",
                iou(med),
                iou(low),
                if contacts { "yes" } else { "none" },
                secs(wall)
            );
        }
    }
    t
}

/// The last runs of the `bsa new` suite: a set and seed, stated objects or `auto:`.
fn table_new_suite() -> String {
    let rows = ledger("new-suite");
    let runs = last_runs(&rows, LAST_RUNS);
    let mut t = String::from(
        "| set / seed | objects | pictures | median IoU | lowest IoU | at 0.90 or more | with a contact before t | commit |\n|---|---|---|---|---|---|---|---|\n",
    );
    for (commit, set, route) in runs {
        // The last row of each picture in the run.
        let mut last: BTreeMap<&str, &Row> = BTreeMap::new();
        for r in rows
            .iter()
            .filter(|r| r.commit == commit && r.set_or_seed == set && r.route == route)
        {
            last.insert(&r.item, r);
        }
        let ious: Vec<f64> = last.values().filter_map(|r| r.iou).collect();
        let (low, at) = last
            .values()
            .filter(|r| r.iou.is_some())
            .min_by(|a, b| a.iou.unwrap_or(0.0).total_cmp(&b.iou.unwrap_or(0.0)))
            .map_or(("-".into(), String::new()), |r| {
                (iou(r.iou), format!(" ({})", r.item))
            });
        let _ = writeln!(
            t,
            "| {set} | {route} | {} | {} | {low}{at} | {} of {} | {} | {commit} |",
            last.len(),
            iou(median(ious.clone())),
            ious.iter().filter(|&&x| x >= 0.90).count(),
            ious.len(),
            last.values()
                .filter(|r| r.contacts.unwrap_or(0) > 0)
                .count()
        );
    }
    t
}

/// The last set of the `bsa new` suite picture by picture: a column of IoU and wall
/// time for each run of it (objects and commit), in the ledger's order.
fn table_new_suite_latest() -> String {
    let rows = ledger("new-suite");
    let Some(latest) = rows.last() else {
        return String::new();
    };
    let set = latest.set_or_seed.clone();
    let mine: Vec<Row> = rows
        .iter()
        .filter(|r| r.set_or_seed == set)
        .cloned()
        .collect();
    let runs: Vec<(String, String, String)> = last_runs(&mine, usize::MAX);
    let mut t = format!("| {set}: picture |");
    for (commit, _, route) in &runs {
        let _ = write!(t, " {route} at {commit}: IoU | wall time |");
    }
    t.push_str("\n|---|");
    t.push_str(&"---|---|".repeat(runs.len()));
    t.push('\n');
    for item in items(&mine) {
        let _ = write!(t, "| {item} |");
        for (commit, _, route) in &runs {
            let r = mine
                .iter()
                .rev()
                .find(|r| r.item == item && &r.route == route && &r.commit == commit);
            let _ = write!(
                t,
                " {} | {} |",
                iou(r.and_then(|r| r.iou)),
                secs(r.and_then(|r| r.seconds))
            );
        }
        t.push('\n');
    }
    t
}

fn table(name: &str) -> String {
    match name {
        "examples" => table_examples(),
        "speed" => table_speed(),
        "make-examples" => table_make_examples(),
        "planted" => table_planted(),
        "new-suite" => table_new_suite(),
        "new-suite-latest" => table_new_suite_latest(),
        other => table_as_recorded(other),
    }
}

/// The fields of a CSV file's lines (RFC 4180: a field in double quotes may hold commas
/// and doubled quotes).
fn csv_rows(text: &str, what: &str) -> Vec<Vec<String>> {
    csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(text.as_bytes())
        .records()
        .map(|r| {
            r.unwrap_or_else(|e| panic!("{what}: {e}"))
                .iter()
                .map(String::from)
                .collect()
        })
        .collect()
}

/// A table as recorded in `results/tables/NAME.csv`: the first row its headers, every
/// cell as shown (an empty cell as one space).
fn table_as_recorded(name: &str) -> String {
    let path = root().join(format!("results/tables/{name}.csv"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "docs/results.md names the table {name:?}, which is neither made from the ledger nor in {}: {e}",
            path.display()
        )
    });
    let rows = csv_rows(&text, &path.display().to_string());
    let width = rows.first().map_or(0, Vec::len);
    assert!(width > 0, "{}: no header row", path.display());
    let line = |cells: &[String]| {
        let mut s = String::from("|");
        for c in cells {
            assert!(
                !c.contains('|'),
                "{}: a cell holds '|': {c}",
                path.display()
            );
            if c.is_empty() {
                s.push_str(" |");
            } else {
                let _ = write!(s, " {c} |");
            }
        }
        s.push('\n');
        s
    };
    let mut t = line(&rows[0]);
    t.push_str(&"|---".repeat(width));
    t.push_str("|\n");
    for r in &rows[1..] {
        assert_eq!(
            r.len(),
            width,
            "{}: a row of {} cells under {width} headers: {r:?}",
            path.display(),
            r.len()
        );
        t.push_str(&line(r));
    }
    t
}

/// The lines of `text` that start a markdown table row (`|`) outside every
/// `<!-- table:NAME -->` ... `<!-- end -->` block, with their line numbers.
fn table_lines_outside_markers(text: &str) -> Vec<(usize, &str)> {
    let mut inside = false;
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let t = line.trim_start();
        if t.starts_with("<!-- table:") {
            inside = true;
        } else if t.starts_with("<!-- end -->") {
            inside = false;
        } else if t.starts_with('|') && !inside {
            out.push((k + 1, line));
        }
    }
    out
}

/// `text` with every marked table made again from the ledger.
fn regenerated(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    let mut seen = Vec::new();
    while let Some(start) = rest.find("<!-- table:") {
        let head_end = start + rest[start..].find("-->").expect("an unclosed table marker") + 3;
        let name = rest[start + "<!-- table:".len()..head_end - 3]
            .trim()
            .to_string();
        let end = head_end
            + rest[head_end..]
                .find("<!-- end -->")
                .unwrap_or_else(|| panic!("table {name} has no <!-- end -->"));
        out.push_str(&rest[..head_end]);
        out.push('\n');
        out.push_str(&table(&name));
        rest = &rest[end..];
        seen.push(name);
    }
    out.push_str(rest);
    for name in TABLES {
        assert!(
            seen.iter().any(|s| s == name),
            "docs/results.md has no table {name}"
        );
    }
    out
}

#[test]
fn docs_results_md_tables_are_the_ledger() {
    let path = root().join("docs/results.md");
    let committed = std::fs::read_to_string(&path).unwrap();
    let made = regenerated(&committed);
    crate::util::generated(
        &path,
        &made,
        "docs/results.md's tables differ from the ledger (results/*.csv)",
        "cargo test --test integration ledger::",
    );
}

#[test]
fn every_table_of_docs_results_md_is_between_markers() {
    let text = std::fs::read_to_string(root().join("docs/results.md")).unwrap();
    let outside = table_lines_outside_markers(&text);
    assert!(
        outside.is_empty(),
        "docs/results.md has table lines outside <!-- table:NAME --> ... <!-- end --> \
         (put the table in results/tables/NAME.csv and mark it):\n{}",
        outside
            .iter()
            .map(|(n, l)| format!("{n}: {l}"))
            .collect::<Vec<_>>()
            .join("\n")
    );
    assert_eq!(
        table_lines_outside_markers("| a |\n<!-- table:x -->\n| b |\n<!-- end -->\n| c |\n"),
        [(1, "| a |"), (5, "| c |")]
    );
}

#[test]
fn every_recorded_table_is_on_the_page_and_reads_back() {
    let page = std::fs::read_to_string(root().join("docs/results.md")).unwrap();
    let dir = root().join("results/tables");
    let mut files = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "csv") {
            continue;
        }
        files += 1;
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        assert!(
            page.contains(&format!("<!-- table:{name} -->")),
            "results/tables/{name}.csv is not on docs/results.md"
        );
        table_as_recorded(&name);
    }
    assert!(files > 0, "results/tables holds no table");
    assert_eq!(
        csv_rows("a,\"b, \"\"c\"\"\",\n,x,\n", "test"),
        [vec!["a", "b, \"c\"", ""], vec!["", "x", ""]]
    );
}

#[test]
fn the_ledger_files_have_the_columns_and_a_commit_on_every_row() {
    let dir = root().join("results");
    let mut files = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "csv") {
            continue;
        }
        files += 1;
        let suite = path.file_stem().unwrap().to_string_lossy().into_owned();
        for r in ledger(&suite) {
            assert!(
                r.commit.len() >= 7 && r.date.len() == 10,
                "results/{suite}.csv: {r:?}"
            );
        }
    }
    assert!(files >= 3, "the ledger has {files} files");
}
