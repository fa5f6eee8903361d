//! The layers point one way: every `crate::` path in the library's code names a module of
//! the same or a lower layer, in the pipeline's order (docs/ARCHITECTURE.md). Test code
//! (`tests.rs` files and everything from a file's first `#[cfg(test)]` on) may reach up.

use std::path::{Path, PathBuf};

/// The library's top-level modules, lowest layer first.
const LAYERS: [&str; 12] = [
    "linalg", "geometry", "shadow", "energy", "scene", "sim", "evaluate", "design", "output",
    "optimize", "budget", "cli",
];

fn rank(module: &str) -> Option<usize> {
    LAYERS.iter().position(|m| *m == module)
}

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            sources(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn every_crate_path_points_to_the_same_or_a_lower_layer() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    files.sort();
    let mut seen = 0;
    let mut wrong = Vec::new();
    for file in &files {
        let rel = file.strip_prefix(&src).unwrap();
        let top = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_str()
            .unwrap();
        let top = top.trim_end_matches(".rs");
        if top == "main" || top == "lib" || file.file_name().unwrap() == "tests.rs" {
            continue;
        }
        let own =
            rank(top).unwrap_or_else(|| panic!("{}: module `{top}` has no layer", rel.display()));
        let text = std::fs::read_to_string(file).unwrap();
        for (n, line) in text.lines().enumerate() {
            if line.trim_start().starts_with("#[cfg(test)]") {
                break;
            }
            let code = line.split("//").next().unwrap();
            for (at, _) in code.match_indices("crate::") {
                let name: String = code[at + 7..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                seen += 1;
                match rank(&name) {
                    Some(r) if r <= own => {}
                    _ => wrong.push(format!("{}:{}: {top} -> {name}", rel.display(), n + 1)),
                }
            }
        }
    }
    assert!(
        seen > 50,
        "only {seen} crate paths found: is this the right folder?"
    );
    assert!(
        wrong.is_empty(),
        "paths that point up a layer:\n{}",
        wrong.join("\n")
    );
}
