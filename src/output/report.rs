//! `report.html`: one self-contained page per solve, for a person. It shows the overlay,
//! the convergence plot, the energy terms, the launch values with their units, the
//! contacts, the stages and, when `bsa budget` has run, the error budget. Every picture
//! is embedded as a `data:` URI, so the page needs no network and no other file: it can
//! be mailed or archived alone.
//!
//! The page is built from the files of the output folder ([`write_report`]), so `solve`
//! and `budget` can both refresh it.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::energy::Term;
use crate::output::files::{self, ExportError};
use crate::output::solution::Solution;

/// The pictures a report embeds, in page order, with their section titles.
const PICTURES: [(&str, &str); 2] = [
    ("overlay.png", "Shadow at t against the target"),
    ("convergence.png", "Convergence"),
];
/// The error budget's pictures, shown when present.
const BUDGET_PICTURES: [&str; 2] = ["budget_hist.png", "budget_tolerances.png"];

/// Escape text for HTML.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Standard base64 (RFC 4648, with padding), for the embedded pictures.
fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(ABC[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

fn img_tag(bytes: &[u8], alt: &str) -> String {
    format!(
        "<img alt=\"{}\" src=\"data:image/png;base64,{}\">",
        esc(alt),
        base64(bytes)
    )
}

/// A PNG of the output folder, or `None` when it is not there.
fn read_optional(path: &Path) -> Result<Option<Vec<u8>>, ExportError> {
    match std::fs::read(path) {
        Ok(b) => Ok(Some(b)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(source) => Err(ExportError::Read {
            path: path.to_path_buf(),
            source,
        }),
    }
}

const STYLE: &str =
    "body{font-family:sans-serif;max-width:1240px;margin:1em auto;padding:0 1em;color:#222}\
h1{margin-bottom:0.2em}table{border-collapse:collapse;margin:0.5em 0 1.5em}\
td,th{border:1px solid #ccc;padding:0.25em 0.6em;text-align:right}\
th{background:#f0f0f0}td:first-child,th:first-child{text-align:left}\
img{max-width:100%;border:1px solid #ddd}pre{background:#f7f7f7;padding:0.8em;overflow-x:auto}\
.summary{font-size:1.1em}";

/// The page for `solution` with the pictures found in `dir`.
pub fn report_html(dir: &Path, s: &Solution) -> Result<String, ExportError> {
    let mut h = String::new();
    head_html(&mut h, s);
    pictures_html(&mut h, dir)?;
    energy_html(&mut h, s);
    launch_html(&mut h, s);
    contacts_html(&mut h, s);
    stages_html(&mut h, s);
    passes_html(&mut h, s);
    budget_html(&mut h, dir, s)?;
    h.push_str("<p><small>Written by bsa (ballistic-shadow-art).</small></p>\n</body></html>\n");
    Ok(h)
}

/// The page's head, its title and the one-paragraph summary of the solve, with a line
/// on the attempts when there were several.
fn head_html(h: &mut String, s: &Solution) {
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>{name}: ballistic shadow art</title><style>{STYLE}</style></head><body>\n\
         <h1>{name}</h1>\n<p class=\"summary\">IoU at t = {t} s: <b>{iou:.4}</b>; total energy \
         {total:.6e}; {samples} samples in {iterations} iterations over {done} of {stages} \
         stages{complete}; {wall:.2} s on {threads} threads; seed {seed}.</p>\n",
        name = esc(&s.scene),
        t = s.t,
        iou = s.iou,
        total = s.total_energy,
        samples = s.samples,
        iterations = s.iterations,
        done = s.stages_completed,
        stages = s.stages_total,
        complete = if s.complete { "" } else { " (stopped early)" },
        wall = s.wall_time_s,
        threads = s.threads,
        seed = s.seed,
    );
    if s.attempts.len() > 1 {
        // A solve of several attempts: each one's picture, and which is shown.
        let each: Vec<String> = s
            .attempts
            .iter()
            .map(|a| {
                let shown = if a.kept { " (shown)" } else { "" };
                format!("{}, {:.2} s{shown}", a.describe(), a.wall_time_s)
            })
            .collect();
        let _ = writeln!(
            h,
            "<p>{} attempts from the start guess: {}.</p>",
            s.attempts.len(),
            esc(&each.join("; "))
        );
    }
}

/// The [`PICTURES`] of `dir` that exist, each under its title.
fn pictures_html(h: &mut String, dir: &Path) -> Result<(), ExportError> {
    for (file, title) in PICTURES {
        if let Some(bytes) = read_optional(&dir.join(file))? {
            let _ = writeln!(h, "<h2>{title}</h2>\n{}", img_tag(&bytes, title));
        }
    }
    Ok(())
}

/// The table of the energy terms at the solution, raw and weighted, and their total.
fn energy_html(h: &mut String, s: &Solution) {
    h.push_str(
        "<h2>Energy terms at the solution</h2>\n<table><tr><th>term</th><th>raw</th>\
         <th>weighted (last stage)</th></tr>\n",
    );
    // The scene's term order, not the file's alphabetical one; then any other key.
    let mut keys: Vec<String> = Term::ALL.iter().map(|t| t.key().to_string()).collect();
    keys.extend(
        s.energy
            .keys()
            .filter(|k| !keys.contains(k))
            .cloned()
            .collect::<Vec<_>>(),
    );
    for key in keys {
        let Some(v) = s.energy.get(&key) else {
            continue;
        };
        let name = Term::from_key(&key).map_or(key.clone(), |t| t.display_name());
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{:.6e}</td><td>{:.6e}</td></tr>",
            esc(&name),
            v.raw,
            v.weighted
        );
    }
    let _ = writeln!(
        h,
        "<tr><th>total</th><th></th><th>{:.6e}</th></tr></table>",
        s.total_energy
    );
}

/// The table of every occluder's launch, velocities with their units.
fn launch_html(h: &mut String, s: &Solution) {
    // Micrometres per second and microradians per second are the precision that
    // matters for a launcher; more digits are the solver's noise.
    h.push_str(
        "<h2>Launch</h2>\n<table><tr><th>occluder</th><th>launched</th>\
         <th>v<sub>x</sub> (m/s)</th><th>v<sub>y</sub> (m/s)</th><th>v<sub>z</sub> (m/s)</th>\
         <th>&omega;<sub>x</sub> (rad/s)</th><th>&omega;<sub>y</sub> (rad/s)</th>\
         <th>&omega;<sub>z</sub> (rad/s)</th></tr>\n",
    );
    for o in &s.occluders {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td>",
            esc(&o.name),
            if o.launched { "yes" } else { "no" }
        );
        for v in o.velocity.iter().chain(&o.angular_velocity) {
            let _ = write!(h, "<td>{v:.6}</td>");
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n");
}

/// The contacts before t: none, or how many and when the first one happens.
fn contacts_html(h: &mut String, s: &Solution) {
    h.push_str("<h2>Contacts before t</h2>\n");
    if s.n_contacts == 0 {
        let _ = writeln!(
            h,
            "<p>No contact before t = {} s: every flight is free.</p>",
            s.t
        );
    } else {
        let _ = writeln!(
            h,
            "<p>{} contacts; the first at {:.4} s (before t = {} s), after which the \
             motion is simulated.</p>",
            s.n_contacts, s.t_sim, s.t
        );
    }
}

/// The table of the solver's stages, a row each.
fn stages_html(h: &mut String, s: &Solution) {
    h.push_str(
        "<h2>Stages</h2>\n<table><tr><th>stage</th><th>iterations</th><th>samples</th>\
         <th>population</th><th>best energy</th><th>IoU</th><th>stop</th>\
         <th>wall time (s)</th></tr>\n",
    );
    for (i, st) in s.stages.iter().enumerate() {
        let _ = writeln!(
            h,
            "<tr><td>{} {}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.6e}</td>\
             <td>{:.4}</td><td>{}</td><td>{:.2}</td></tr>",
            i + 1,
            esc(&st.name),
            st.iterations,
            st.samples,
            st.population,
            st.best_energy,
            st.iou,
            esc(&st.stop),
            st.wall_time_s
        );
    }
    h.push_str("</table>\n");
}

/// What launcher the solution needs, from `dir/launcher.md` (`bsa solve` writes it); the
/// frontier of the designs `bsa new --launcher` tried, from the scene's folder; and the
/// error budget when `bsa budget` has written `dir/budget.md`.
fn budget_html(h: &mut String, dir: &Path, s: &Solution) -> Result<(), ExportError> {
    markdown_html(h, dir, "launcher.md", "What launcher it needs", &[])?;
    if let Some(scene_dir) = s.scene_file.as_deref().and_then(|f| Path::new(f).parent()) {
        let title = "The designs tried for the launcher";
        markdown_html(h, scene_dir, "frontier.md", title, &["frontier.png"])?;
    }
    markdown_html(h, dir, "budget.md", "Error budget", &BUDGET_PICTURES)
}

/// A section titled `title` from the Markdown file `name` of `dir`: the `pictures` found
/// in `dir`, then the Markdown as text; nothing when the file is absent.
fn markdown_html(
    h: &mut String,
    dir: &Path,
    name: &str,
    title: &str,
    pictures: &[&str],
) -> Result<(), ExportError> {
    let Some(md) = read_optional(&dir.join(name))? else {
        return Ok(());
    };
    let _ = writeln!(h, "<h2>{title}</h2>");
    for &file in pictures {
        if let Some(bytes) = read_optional(&dir.join(file))? {
            let _ = writeln!(h, "<p>{}</p>", img_tag(&bytes, file));
        }
    }
    // The budget's Markdown as written: its tables read as text, and its image
    // links (shown above) are dropped.
    let text: String = String::from_utf8_lossy(&md)
        .lines()
        .filter(|l| !l.starts_with("!["))
        .map(|l| format!("{l}\n"))
        .collect();
    let _ = writeln!(h, "<pre>{}</pre>", esc(&text));
    Ok(())
}

/// The passes of the solver's schedule that ran: a line per kind of pass (how often,
/// its samples, its time and the IoU it gained in all), then every pass in order.
fn passes_html(h: &mut String, s: &Solution) {
    if s.passes.is_empty() {
        return;
    }
    h.push_str(
        "<h2>Passes</h2>\n<table><tr><th>pass</th><th>ran</th><th>samples</th>\
         <th>wall time (s)</th><th>IoU gained</th><th>moves taken</th></tr>\n",
    );
    let mut kinds: Vec<&str> = Vec::new();
    for p in &s.passes {
        if !kinds.contains(&p.pass.as_str()) {
            kinds.push(&p.pass);
        }
    }
    for kind in kinds {
        let of: Vec<_> = s.passes.iter().filter(|p| p.pass == kind).collect();
        // The moves taken, by name in the order first taken: "pose fit 9, seat 2".
        let mut taken: Vec<(&str, usize)> = Vec::new();
        for m in of.iter().flat_map(|p| &p.moves) {
            match taken.iter_mut().find(|t| t.0 == m.name) {
                Some(t) => t.1 += 1,
                None => taken.push((&m.name, 1)),
            }
        }
        let taken: Vec<String> = taken.iter().map(|(n, c)| format!("{n} {c}")).collect();
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.2}</td><td>{:+.4}</td><td>{}</td></tr>",
            esc(kind),
            of.len(),
            of.iter().map(|p| p.samples).sum::<usize>(),
            of.iter().map(|p| p.wall_time_s).sum::<f64>(),
            of.iter().map(|p| p.iou_after - p.iou_before).sum::<f64>(),
            esc(&taken.join(", ")),
        );
    }
    h.push_str(
        "</table>\n<details><summary>Every pass</summary>\n<table><tr><th>attempt</th>\
         <th>stage</th><th>pass</th><th>IoU before</th><th>IoU after</th><th>samples</th>\
         <th>wall time (s)</th></tr>\n",
    );
    for p in &s.passes {
        let stage = s.stages.get(p.stage).map_or("", |st| st.name.as_str());
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{} {}</td><td>{}</td><td>{:.4}</td><td>{:.4}</td><td>{}</td>\
             <td>{:.3}</td></tr>",
            p.attempt + 1,
            p.stage + 1,
            esc(stage),
            esc(&p.pass),
            p.iou_before,
            p.iou_after,
            p.samples,
            p.wall_time_s
        );
    }
    h.push_str("</table></details>\n");
}

/// Write `dir/report.html` for `solution`; returns its path.
pub fn write_report(dir: &Path, s: &Solution) -> Result<PathBuf, ExportError> {
    let path = dir.join("report.html");
    files::write_atomic(&path, report_html(dir, s)?.as_bytes())?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc_4648_vectors() {
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), coded);
        }
    }

    fn solution() -> Solution {
        let v = serde_json::json!({
            "scene": "demo <1>", "scene_file": null, "seed": 1, "t": 1.2,
            "stages_total": 1, "stages_completed": 1, "complete": true,
            "occluders": [{"name": "ball", "launched": true,
                "velocity_m_s": [0.000_035_271_9, 1.5, 6.25],
                "angular_velocity_rad_s": [0.1, 0.2, 0.3]}],
            "energy": {"xor": {"raw": 3.0, "weighted": 900.0},
                       "d0": {"raw": 1.0, "weighted": 2.0}},
            "total_energy": 902.0, "iou": 0.99, "t_sim": 1.2, "n_contacts": 0,
            "samples": 10, "iterations": 2, "wall_time_s": 0.1, "threads": 2,
            "time_per_term_us": {},
            "stages": [{"name": "fine", "iterations": 2, "samples": 10, "population": 5,
                "best_energy": 902.0, "iou": 0.99, "stop": "iteration cap",
                "wall_time_s": 0.1}],
            "passes": [
                {"attempt": 0, "stage": 0, "pass": "moves", "iou_before": 0.5,
                 "iou_after": 0.6, "samples": 4, "wall_time_s": 0.01,
                 "moves": [{"move": "seat", "iou_before": 0.5, "iou_after": 0.55},
                           {"move": "fill", "iou_before": 0.55, "iou_after": 0.58},
                           {"move": "seat", "iou_before": 0.58, "iou_after": 0.6}]},
                {"attempt": 0, "stage": 0, "pass": "runs", "iou_before": 0.6,
                 "iou_after": 0.99, "samples": 6, "wall_time_s": 0.09}]
        });
        serde_json::from_value(v).unwrap()
    }

    #[test]
    fn page_is_self_contained_with_units_terms_in_order_and_the_budget_when_present() {
        let dir = crate::test_temp::TempPath::dir("bsa-report", "page");
        std::fs::write(dir.join("overlay.png"), b"png bytes").unwrap();
        let page = report_html(&dir, &solution()).unwrap();
        assert!(!page.contains("http://") && !page.contains("https://"));
        assert!(page.contains("demo &lt;1&gt;"), "names are escaped");
        assert!(page.contains(&format!("data:image/png;base64,{}", base64(b"png bytes"))));
        assert!(page.contains("(m/s)") && page.contains("(rad/s)"));
        // Micrometres per second, not 17 digits.
        assert!(page.contains("<td>0.000035</td>"), "{page}");
        // The scene's term order (d0 before xor), with the one vocabulary.
        let (d0, xor) = (
            page.find("d0 (0th moment)").unwrap(),
            page.find(">xor<").unwrap(),
        );
        assert!(d0 < xor);
        assert!(page.contains("No contact before t"));
        // Every pass that ran, and a line per kind with the IoU it gained.
        assert!(page
            .contains("<td>runs</td><td>1</td><td>6</td><td>0.09</td><td>+0.3900</td><td></td>"));
        // The moves a kind of pass took, counted by name in the order first taken.
        assert!(
            page.contains("<td>+0.1000</td><td>seat 2, fill 1</td>"),
            "{page}"
        );
        assert!(page.contains("<td>1 fine</td><td>moves</td><td>0.5000</td><td>0.6000</td>"));
        assert!(!page.contains("Error budget"));
        std::fs::write(
            dir.join("budget.md"),
            "# Budget\n![h](budget_hist.png)\n| a |\n",
        )
        .unwrap();
        let page = report_html(&dir, &solution()).unwrap();
        assert!(page.contains("Error budget") && page.contains("| a |"));
        assert!(
            !page.contains("![h]"),
            "image links of the Markdown are dropped"
        );
    }

    #[test]
    fn html_text_is_escaped() {
        assert_eq!(esc("<a & \"b\">"), "&lt;a &amp; &quot;b&quot;&gt;");
    }
}
