//! The layers point one way: every `crate::` path in the library's code names a module of
//! the same or a lower layer, in the pipeline's order (docs/ARCHITECTURE.md). And only
//! the modules docs/ARCHITECTURE.md names touch the file system. Test code (`tests.rs`
//! files and everything from a file's first `#[cfg(test)]` on) may do either.

use std::path::{Path, PathBuf};

/// The library's top-level modules, lowest layer first.
const LAYERS: [&str; 13] = [
    "linalg", "geometry", "shadow", "energy", "scene", "sim", "evaluate", "design", "output",
    "optimize", "budget", "compose", "cli",
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

/// The files (or folders, ending in `/`) under `src/` that may touch the file system, as
/// docs/ARCHITECTURE.md's invariant names them: the command line, scene loading (which
/// the launch files of `output::launches` are read by) with the OBJ reader it calls, and
/// the output folder's files (`output::report` reads the pictures back to embed them).
const FILE_SYSTEM: [&str; 6] = [
    "cli/",
    "scene/",
    "geometry/shape/mod.rs",
    "output/files.rs",
    "output/report.rs",
    "output/launches.rs",
];

/// What touches the file system in a line of code: `std::fs` and the path queries that
/// look at it, the readers of other crates, and the readers of the allowed modules
/// (so that a module cannot reach the disk through them either).
const TOUCHES: [&str; 21] = [
    "std::fs",
    " fs::",
    "(fs::",
    "File::open",
    "File::create",
    "OpenOptions",
    ".exists()",
    ".try_exists(",
    ".is_file()",
    ".is_dir()",
    ".metadata(",
    ".canonicalize(",
    ".read_dir(",
    "tobj::load",
    "image::open",
    "load_obj",
    "read_input(",
    "read_input_text(",
    "scene::load(",
    "path_kind",
    "files::",
];

#[test]
fn only_the_modules_named_in_the_architecture_touch_the_file_system() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    files.sort();
    let mut allowed_hits = 0;
    let mut wrong = Vec::new();
    for file in &files {
        let rel = file.strip_prefix(&src).unwrap();
        let rel = rel.to_str().unwrap().replace('\\', "/");
        if file.file_name().unwrap() == "tests.rs" {
            continue;
        }
        let allowed = FILE_SYSTEM.iter().any(|a| {
            if a.ends_with('/') {
                rel.starts_with(a)
            } else {
                rel == *a
            }
        });
        let text = std::fs::read_to_string(file).unwrap();
        for (n, line) in text.lines().enumerate() {
            if line.trim_start().starts_with("#[cfg(test)]") {
                break;
            }
            let code = line.split("//").next().unwrap();
            if let Some(what) = TOUCHES.iter().find(|t| code.contains(*t)) {
                if allowed {
                    allowed_hits += 1;
                } else {
                    wrong.push(format!("{rel}:{}: {what}: {}", n + 1, line.trim()));
                }
            }
        }
    }
    assert!(
        allowed_hits > 10,
        "only {allowed_hits} file system uses found in the allowed modules: is this the right folder?"
    );
    assert!(
        wrong.is_empty(),
        "file system use outside the modules docs/ARCHITECTURE.md allows ({}):\n{}",
        FILE_SYSTEM.join(", "),
        wrong.join("\n")
    );
}
