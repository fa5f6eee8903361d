//! Writing results: `solution.json`, `shadow.png`, `overlay.png`, `preview.png`,
//! `convergence.csv` and `convergence.png` in an output folder.
//!
//! Main functions: [`write_solution`], [`read_solution`], [`write_pictures`],
//! [`ConvergenceCsv`], [`write_convergence_plot`], [`read_convergence`]. Every file is
//! written atomically (a temporary file in the same folder, then a rename), so an
//! interrupted run never leaves a half-written file behind; the one exception,
//! `convergence.csv`, grows by synced appends of whole stages (see [`ConvergenceCsv`]).

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::energy::{Term, TERM_COUNT};
use crate::output::picture;
use crate::output::solution::{SampleRecord, Solution};
use crate::shadow::mask::Mask;

/// Why an output could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("cannot write {path}")]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot read {path}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path} is not a valid solution file: {message}")]
    BadSolution { path: PathBuf, message: String },
    #[error("{path} is not a valid convergence table: {message}")]
    BadConvergence { path: PathBuf, message: String },
    #[error("cannot encode {path}: {message}")]
    Encode { path: PathBuf, message: String },
    #[error("cannot draw {path}")]
    Picture {
        path: PathBuf,
        #[source]
        source: picture::PictureError,
    },
}

type Result<T> = std::result::Result<T, ExportError>;

/// Write `bytes` to `path` atomically.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let err = |source| ExportError::Write {
        path: path.to_path_buf(),
        source,
    };
    if let Some(dir) = path.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir).map_err(err)?;
        }
    }
    let name = path.file_name().and_then(|s| s.to_str()).unwrap_or("out");
    let tmp = path.with_file_name(format!(".{name}.tmp{}", std::process::id()));
    let written = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    // A failed write (a full disk) must not leave its temporary file behind, or the
    // disk stays full.
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written.map_err(err)
}

fn png_bytes<P, C>(img: &image::ImageBuffer<P, C>, path: &Path) -> Result<Vec<u8>>
where
    P: image::Pixel<Subpixel = u8> + image::PixelWithColorType,
    C: std::ops::Deref<Target = [u8]>,
{
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    use image::ImageEncoder;
    let mut out = Vec::new();
    // Fast compression: these are previews written while the optimizer runs.
    PngEncoder::new_with_quality(&mut out, CompressionType::Fast, FilterType::Adaptive)
        .write_image(img.as_raw(), img.width(), img.height(), P::COLOR_TYPE)
        .map_err(|e| ExportError::Encode {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
    Ok(out)
}

/// Write an image as PNG, atomically.
pub fn save_png<P, C>(img: &image::ImageBuffer<P, C>, path: &Path) -> Result<()>
where
    P: image::Pixel<Subpixel = u8> + image::PixelWithColorType,
    C: std::ops::Deref<Target = [u8]>,
{
    write_atomic(path, &png_bytes(img, path)?)
}

/// `path` relative to the folder `base`, both made absolute first (without resolving
/// links); `None` when they share no root.
fn relative_to(path: &Path, base: &Path) -> Option<PathBuf> {
    use std::path::Component;
    let path = std::path::absolute(path).ok()?;
    let base = std::path::absolute(base).ok()?;
    // `absolute` keeps `..` components; dropping them against their parent keeps the
    // comparison below purely lexical and right for paths without symbolic links.
    fn normal(p: &Path) -> Vec<Component<'_>> {
        let mut out: Vec<Component> = Vec::new();
        for c in p.components() {
            match c {
                Component::ParentDir if matches!(out.last(), Some(Component::Normal(_))) => {
                    out.pop();
                }
                Component::CurDir => {}
                c => out.push(c),
            }
        }
        out
    }
    let (p, b) = (normal(&path), normal(&base));
    if p.first() != b.first() {
        return None;
    }
    let common = p.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut rel = PathBuf::new();
    for _ in common..b.len() {
        rel.push("..");
    }
    for c in &p[common..] {
        rel.push(c.as_os_str());
    }
    Some(rel)
}

/// `solution.json`. The scene file is recorded relative to the output folder, so that a
/// results folder moved or cloned together with its scene still finds it, and no
/// absolute path of one machine is written; [`read_solution`] turns it back into a path
/// usable from the current folder.
pub fn write_solution(dir: &Path, s: &Solution) -> Result<()> {
    let path = dir.join("solution.json");
    let relative;
    let s = match s
        .scene_file
        .as_deref()
        .and_then(|f| relative_to(Path::new(f), dir))
    {
        Some(rel) => {
            relative = Solution {
                scene_file: Some(rel.display().to_string()),
                ..s.clone()
            };
            &relative
        }
        None => s,
    };
    let text = serde_json::to_string_pretty(s).map_err(|e| ExportError::Encode {
        path: path.clone(),
        message: e.to_string(),
    })?;
    write_atomic(&path, text.as_bytes())
}

/// Read a solution file.
pub fn read_solution(path: &Path) -> Result<Solution> {
    let text = crate::scene::read_input_text(path).map_err(|source| ExportError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let mut s: Solution = serde_json::from_str(&text).map_err(|e| ExportError::BadSolution {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    // A relative scene file is relative to the solution's folder (older files hold an
    // absolute path, which `join` keeps as it is).
    if let (Some(f), Some(dir)) = (&s.scene_file, path.parent()) {
        s.scene_file = Some(dir.join(f).display().to_string());
    }
    Ok(s)
}

/// The overlay of a shadow on the target at 1:1 (agreement grey, missed target blue,
/// extra shadow red) with `title`, the IoU and a legend below it.
pub fn overlay(
    target: &Mask,
    shadow: &Mask,
    title: &str,
) -> std::result::Result<image::RgbImage, picture::PictureError> {
    picture::overlay_figure(
        target.width(),
        target.height(),
        &|x, y| target.get(x, y),
        &|x, y| shadow.get(x, y),
        title,
    )
}

pub fn save_overlay(path: &Path, target: &Mask, shadow: &Mask, title: &str) -> Result<()> {
    let img = overlay(target, shadow, title).map_err(|source| ExportError::Picture {
        path: path.to_path_buf(),
        source,
    })?;
    save_png(&img, path)
}

/// `shadow.png` (the mask at t) and `overlay.png` (captioned with `title`).
pub fn write_pictures(dir: &Path, target: &Mask, shadow: &Mask, title: &str) -> Result<()> {
    let img = picture::mask_image(shadow.width(), shadow.height(), &|x, y| shadow.get(x, y));
    save_png(&img, &dir.join("shadow.png"))?;
    save_overlay(&dir.join("overlay.png"), target, shadow, title)
}

/// `preview.png`: the overlay of the best shadow so far.
pub fn write_preview(dir: &Path, target: &Mask, shadow: &Mask) -> Result<()> {
    save_overlay(
        &dir.join("preview.png"),
        target,
        shadow,
        "preview: best shadow so far",
    )
}

/// Save a plot as `<stem>.png` and `<stem>.svg` in `dir`.
pub fn save_figure(dir: &Path, stem: &str, figure: &picture::plot::Figure) -> Result<()> {
    save_png(&figure.png, &dir.join(format!("{stem}.png")))?;
    write_atomic(&dir.join(format!("{stem}.svg")), figure.svg.as_bytes())
}

/// `convergence.csv` (every sample: stage, iteration, each weighted term, total), grown
/// stage by stage while a solve runs: [`ConvergenceCsv::create`] writes the header and
/// the rows kept from earlier stages atomically, then [`ConvergenceCsv::append`] adds each
/// stage's rows and syncs them, so a stage costs only its own rows (not the whole table
/// again). A solve appends a stage's rows before it records the stage as completed in
/// `solution.json`, so after an interruption the table holds every completed stage, and
/// at most a cut-off last row that [`read_convergence`] ignores.
pub struct ConvergenceCsv {
    path: PathBuf,
}

impl ConvergenceCsv {
    /// Start `dir/convergence.csv` with its header and `records`.
    pub fn create(dir: &Path, records: &[SampleRecord]) -> Result<ConvergenceCsv> {
        let path = dir.join("convergence.csv");
        // Stages are numbered from 1 here as in the terminal and `eval --stage`; the
        // column's name says so, and tells these files from older ones whose `stage`
        // counted from 0 (still read by `read_convergence`).
        let mut header = vec!["stage_number".to_string(), "iteration".to_string()];
        header.extend(Term::ALL.iter().map(|t| t.key().to_string()));
        header.push("total".into());
        let mut bytes = encode_rows(&path, |w| w.write_record(&header))?;
        bytes.extend(encode_records(records));
        write_atomic(&path, &bytes)?;
        Ok(ConvergenceCsv { path })
    }

    /// Append rows, synced to disk before returning.
    pub fn append(&self, records: &[SampleRecord]) -> Result<()> {
        let bytes = encode_records(records);
        let err = |source| ExportError::Write {
            path: self.path.clone(),
            source,
        };
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(&self.path)
            .map_err(err)?;
        f.write_all(&bytes).map_err(err)?;
        f.sync_data().map_err(err)
    }
}

/// The CSV lines of `records`. Written by hand rather than through `csv`: every field is
/// an integer or a number in Rust's `{:e}` form (digits, `.`, `-`, `e`, `inf`, `NaN`),
/// which CSV never quotes, and a solve writes tens of thousands of rows on a thread that
/// shares the cores with the solver.
fn encode_records(records: &[SampleRecord]) -> Vec<u8> {
    use std::fmt::Write as _;
    let mut text = String::with_capacity(records.len() * 160);
    for r in records {
        // Writing into a String cannot fail.
        let _ = write!(text, "{},{}", r.stage + 1, r.iteration);
        for x in r.terms.iter().chain([&r.total]) {
            let _ = write!(text, ",{x:e}");
        }
        text.push('\n');
    }
    text.into_bytes()
}

/// CSV text of the rows that `f` writes (no header line of its own).
fn encode_rows(
    path: &Path,
    f: impl FnOnce(&mut csv::Writer<&mut Vec<u8>>) -> csv::Result<()>,
) -> Result<Vec<u8>> {
    let enc = |message: String| ExportError::Encode {
        path: path.to_path_buf(),
        message,
    };
    let mut bytes = Vec::new();
    let mut w = csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(&mut bytes);
    f(&mut w).map_err(|e| enc(e.to_string()))?;
    w.flush().map_err(|e| enc(e.to_string()))?;
    drop(w);
    Ok(bytes)
}

/// `convergence.png` and `convergence.svg`: every term and the total against the sample
/// index, stage by stage (see [`picture::plot::convergence`]).
pub fn write_convergence_plot(
    dir: &Path,
    scene: &str,
    stage_names: &[String],
    records: &[SampleRecord],
) -> Result<()> {
    let data = picture::plot::ConvergenceData {
        scene: scene.to_string(),
        stage_names: stage_names.to_vec(),
        term_names: Term::ALL.iter().map(|t| t.display_name()).collect(),
        rows: records
            .iter()
            .map(|r| picture::plot::ConvergenceRow {
                stage: r.stage,
                iteration: r.iteration,
                terms: r.terms.to_vec(),
                total: r.total,
            })
            .collect(),
    };
    let figure = picture::plot::convergence(&data).map_err(|source| ExportError::Picture {
        path: dir.join("convergence.png"),
        source,
    })?;
    save_figure(dir, "convergence", &figure)
}

/// Write rows as a CSV file (header from the field names), atomically.
pub fn write_csv<T: serde::Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    write_atomic(path, &csv_bytes(path, rows)?)
}

/// The bytes of a CSV file of `rows` (header from the field names); `path` names the
/// file in an error.
pub fn csv_bytes<T: serde::Serialize>(path: &Path, rows: &[T]) -> Result<Vec<u8>> {
    let enc = |message: String| ExportError::Encode {
        path: path.to_path_buf(),
        message,
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r).map_err(|e| enc(e.to_string()))?;
    }
    w.into_inner().map_err(|e| enc(e.to_string()))
}

/// [`write_atomic`] unless the file already holds exactly `bytes`, so that rewriting an
/// unchanged export keeps its modification time; true if it wrote.
pub fn write_if_changed(path: &Path, bytes: &[u8]) -> Result<bool> {
    if std::fs::read(path).is_ok_and(|old| old == bytes) {
        return Ok(false);
    }
    write_atomic(path, bytes)?;
    Ok(true)
}

/// Read `convergence.csv` back (for `--resume`), keeping the rows of stages below `stages`.
pub fn read_convergence(path: &Path, stages: usize) -> Result<Vec<SampleRecord>> {
    let bad = |message: String| ExportError::BadConvergence {
        path: path.to_path_buf(),
        message,
    };
    let mut r = csv::Reader::from_path(path).map_err(|e| bad(e.to_string()))?;
    // Files written before stages were numbered from 1 name the column `stage`.
    let first = match r.headers().map_err(|e| bad(e.to_string()))?.get(0) {
        Some("stage") => 0,
        _ => 1,
    };
    let mut out = Vec::new();
    // A malformed row is an error unless it is the last one: a solve stopped in the
    // middle of appending a stage leaves a cut-off last row of a stage that was not
    // completed (see `ConvergenceCsv`).
    let mut damaged = None;
    for row in r.records() {
        if let Some(e) = damaged.take() {
            return Err(e);
        }
        let row = match row {
            Ok(row) if row.len() == TERM_COUNT + 3 => row,
            Ok(row) => {
                damaged = Some(bad(format!(
                    "a row has {} columns, expected {}",
                    row.len(),
                    TERM_COUNT + 3
                )));
                continue;
            }
            Err(e) => {
                damaged = Some(bad(e.to_string()));
                continue;
            }
        };
        let num = |i: usize| -> Result<f64> {
            row[i]
                .parse::<f64>()
                .map_err(|e| bad(format!("`{}`: {e}", &row[i])))
        };
        let stage = row[0]
            .parse::<usize>()
            .map_err(|e| bad(e.to_string()))?
            .checked_sub(first)
            .ok_or_else(|| bad(format!("stage {} is below {first}", &row[0])))?;
        if stage >= stages {
            continue;
        }
        let mut terms = [0.0; TERM_COUNT];
        for (k, t) in terms.iter_mut().enumerate() {
            *t = num(2 + k)?;
        }
        out.push(SampleRecord {
            stage,
            iteration: row[1].parse::<usize>().map_err(|e| bad(e.to_string()))?,
            terms,
            total: num(TERM_COUNT + 2)?,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn records(stages: usize, per_stage: usize) -> Vec<SampleRecord> {
        (0..stages * per_stage)
            .map(|k| SampleRecord {
                stage: k / per_stage,
                iteration: k % per_stage,
                terms: std::array::from_fn(|t| (k * 10 + t) as f64 * 0.125),
                total: k as f64 + 0.5,
            })
            .collect()
    }

    fn dir(name: &str) -> crate::test_temp::TempPath {
        crate::test_temp::TempPath::dir("bsa-files", name)
    }

    #[test]
    fn convergence_grown_by_appends_reads_back_whole() {
        let d = dir("appends");
        let all = records(3, 4);
        let csv = ConvergenceCsv::create(&d, &all[..4]).unwrap();
        csv.append(&all[4..8]).unwrap();
        csv.append(&all[8..]).unwrap();
        let path = d.join("convergence.csv");
        assert_eq!(read_convergence(&path, 3).unwrap(), all);
        // Only the completed stages are kept on resume.
        assert_eq!(read_convergence(&path, 2).unwrap(), &all[..8]);
        // The same bytes as a table written in one go.
        let d2 = dir("one-go");
        ConvergenceCsv::create(&d2, &all).unwrap();
        assert_eq!(
            std::fs::read(&path).unwrap(),
            std::fs::read(d2.join("convergence.csv")).unwrap()
        );
    }

    #[test]
    fn hand_written_rows_are_the_csv_crates_bytes() {
        let odd = [
            0.0,
            -0.0,
            1e300,
            -2.5e-300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
            123456.789,
        ];
        let mut all = records(2, 3);
        for (k, r) in all.iter_mut().enumerate() {
            for (t, x) in r.terms.iter_mut().enumerate() {
                *x = odd[(k + t) % odd.len()];
            }
            r.total = odd[k % odd.len()];
        }
        let expected = encode_rows(Path::new("x.csv"), |w| {
            for r in &all {
                let mut row = vec![(r.stage + 1).to_string(), r.iteration.to_string()];
                row.extend(r.terms.iter().chain([&r.total]).map(|x| format!("{x:e}")));
                w.write_record(&row)?;
            }
            Ok(())
        })
        .unwrap();
        assert_eq!(
            String::from_utf8(encode_records(&all)).unwrap(),
            String::from_utf8(expected).unwrap()
        );
    }

    #[test]
    fn relative_paths_climb_out_of_the_base_and_down_to_the_file() {
        assert_eq!(
            relative_to(
                Path::new("/a/scenes/m/scene.json"),
                Path::new("/a/export/m")
            ),
            Some(PathBuf::from("../../scenes/m/scene.json"))
        );
        assert_eq!(
            relative_to(Path::new("/a/b/../c/s.json"), Path::new("/a/c")),
            Some(PathBuf::from("s.json"))
        );
        // From the current folder, as the solver records it and a reader resolves it.
        let rel = relative_to(Path::new("scenes/m/scene.json"), Path::new("export/m")).unwrap();
        assert_eq!(rel, PathBuf::from("../../scenes/m/scene.json"));
    }

    #[test]
    fn convergence_numbers_stages_from_1_and_reads_older_tables_from_0() {
        let d = dir("numbering");
        let all = records(2, 2);
        ConvergenceCsv::create(&d, &all).unwrap();
        let path = d.join("convergence.csv");
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("stage_number,iteration,d0,"), "{text}");
        assert!(text.lines().nth(1).unwrap().starts_with("1,0,"));
        // An older table: column `stage`, stages from 0.
        let old = text
            .replacen("stage_number", "stage", 1)
            .lines()
            .enumerate()
            .map(|(i, l)| match (i, l.split_once(',')) {
                (0, _) | (_, None) => format!("{l}\n"),
                (_, Some((n, rest))) => format!("{},{rest}\n", n.parse::<usize>().unwrap() - 1),
            })
            .collect::<String>();
        let old_path = d.join("old.csv");
        std::fs::write(&old_path, old).unwrap();
        assert_eq!(read_convergence(&old_path, 2).unwrap(), all);
        assert_eq!(read_convergence(&path, 2).unwrap(), all);
    }

    #[test]
    fn a_cut_off_last_row_is_ignored_and_a_damaged_middle_row_is_not() {
        let d = dir("cut");
        let all = records(2, 3);
        ConvergenceCsv::create(&d, &all).unwrap();
        let path = d.join("convergence.csv");
        let text = std::fs::read_to_string(&path).unwrap();
        // Cut inside the last row's first field: one column left.
        let cut = text
            .rfind('\n')
            .map_or(0, |_| text.trim_end().rfind('\n').unwrap() + 2);
        std::fs::write(&path, &text[..cut]).unwrap();
        assert_eq!(read_convergence(&path, 1).unwrap(), &all[..3]);
        // The same damage in the middle of the table is an error.
        let lines: Vec<&str> = text.lines().collect();
        let mut damaged = lines.clone();
        damaged[2] = "0";
        std::fs::write(&path, damaged.join("\n") + "\n").unwrap();
        assert!(read_convergence(&path, 2).is_err());
    }
}
