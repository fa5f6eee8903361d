//! The layers point one way: every `crate::` path in the library's code names a module of
//! the same or a lower layer, in the pipeline's order (docs/ARCHITECTURE.md). And only
//! the modules docs/ARCHITECTURE.md names touch the file system. Test code (`tests.rs`
//! files and everything from a file's first `#[cfg(test)]` on) may do either. And the
//! code stays in pieces one can read: no function over [`MAX_FUNCTION_LINES`], no file
//! over [`MAX_FILE_LINES`] before its tests.

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

/// The library's folder and its source files, sorted.
fn library() -> (PathBuf, Vec<PathBuf>) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    files.sort();
    (src, files)
}

#[test]
fn every_crate_path_points_to_the_same_or_a_lower_layer() {
    let (src, files) = library();
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
    let (src, files) = library();
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

/// Lines of a function at most, from its `fn` line to its closing brace.
const MAX_FUNCTION_LINES: usize = 120;

/// Lines of a source file at most before its first `#[cfg(test)]`.
const MAX_FILE_LINES: usize = 800;

/// The change of brace depth over `line`, outside strings, characters and comments.
/// `in_string` carries a string literal over lines.
fn brace_change(line: &str, in_string: &mut bool) -> i64 {
    let (mut change, mut chars) = (0, line.chars().peekable());
    while let Some(c) = chars.next() {
        if *in_string {
            match c {
                '\\' => {
                    chars.next();
                }
                '"' => *in_string = false,
                _ => {}
            }
            continue;
        }
        match c {
            '"' => *in_string = true,
            '/' if chars.peek() == Some(&'/') => break,
            // A character literal: '{', '}', '"' or an escape.
            '\'' => {
                let rest: String = chars.clone().take(3).collect();
                if rest.starts_with("\\") && rest.ends_with('\'') {
                    chars.nth(2);
                } else if rest.chars().nth(1) == Some('\'') {
                    chars.nth(1);
                }
            }
            '{' => change += 1,
            '}' => change -= 1,
            _ => {}
        }
    }
    change
}

/// The name of the function a line begins, if it does.
fn function_name(line: &str) -> Option<&str> {
    let mut words = line.split_whitespace();
    loop {
        match words.next()? {
            w if w == "pub" || w.starts_with("pub(") => {}
            "const" | "async" | "unsafe" | "extern" => {}
            "fn" => return words.next()?.split(['<', '(']).next(),
            _ => return None,
        }
    }
}

#[test]
fn no_function_is_over_120_lines_and_no_file_over_800_before_its_tests() {
    let (src, files) = library();
    let (mut functions, mut long) = (0, Vec::new());
    for file in &files {
        let rel = file.strip_prefix(&src).unwrap().display().to_string();
        let text = std::fs::read_to_string(file).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let before_tests = lines
            .iter()
            .position(|l| l.trim_start().starts_with("#[cfg(test)]"))
            .unwrap_or(lines.len());
        if file.file_name().unwrap() != "tests.rs" && before_tests > MAX_FILE_LINES {
            long.push(format!("{rel}: {before_tests} lines before its tests"));
        }
        for (start, line) in lines.iter().enumerate() {
            let Some(name) = function_name(line) else {
                continue;
            };
            let (mut depth, mut opened, mut in_string) = (0, false, false);
            for (k, l) in lines.iter().enumerate().skip(start) {
                if !opened && l.trim_end().ends_with(';') && !l.contains('{') {
                    break; // a declaration without a body
                }
                depth += brace_change(l, &mut in_string);
                opened |= depth > 0;
                if opened && depth == 0 {
                    functions += 1;
                    let n = k - start + 1;
                    if n > MAX_FUNCTION_LINES {
                        long.push(format!("{rel}:{}: fn {name}: {n} lines", start + 1));
                    }
                    break;
                }
            }
        }
    }
    assert!(
        functions > 1000,
        "only {functions} functions found: is this the right folder?"
    );
    assert!(long.is_empty(), "too long:\n{}", long.join("\n"));
}
