//! `report.html` in a real browser: a quick solve writes the page, headless Chromium
//! (Debian's `chromium` package) renders it, and the screenshot must show the overlay
//! in its colours and the tables; the page must not reach for the network.

use std::path::Path;
use std::process::Command;

use crate::util::{quick_solve, require, root, tmpdir};

/// The overlay's agreement grey (`bsa::output::picture::AGREE`).
const AGREE: [u8; 3] = [120, 120, 120];
/// The table headers' background (#f0f0f0 in the page's style).
const TABLE_HEADER: [u8; 3] = [240, 240, 240];

#[test]
#[ignore = "needs Chromium (apt-get install chromium); run by scripts/test.sh"]
fn report_page_renders_the_overlay_and_tables_in_headless_chromium() {
    let chromium = Path::new("/usr/bin/chromium");
    require(chromium, "apt-get install -y chromium");
    let out = quick_solve(&root().join("scenes/mickey"), "report");
    let page = out.join("report.html");
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(
        !html.contains("http://") && !html.contains("https://"),
        "the page must be self-contained"
    );
    for part in [
        "<table",
        "data:image/png;base64,",
        "Launch",
        "v<sub>x</sub> (m/s)",
    ] {
        assert!(html.contains(part), "{part} missing from the page");
    }

    let work = tmpdir("report-chromium");
    let shot = work.join("report.png");
    let status = Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--hide-scrollbars",
            "--force-device-scale-factor=1",
        ])
        .arg(format!(
            "--user-data-dir={}",
            work.join("profile").display()
        ))
        .arg(format!("--screenshot={}", shot.display()))
        .arg("--window-size=1280,2000")
        .arg(format!("file://{}", page.canonicalize().unwrap().display()))
        .output()
        .expect("run chromium");
    assert!(
        shot.is_file(),
        "no screenshot: {}",
        String::from_utf8_lossy(&status.stderr)
    );
    let img = image::open(&shot).unwrap().to_rgb8();
    let count = |c: [u8; 3]| img.pixels().filter(|p| p.0 == c).count();
    // Mickey's target is about 84,000 pixels, shown at 1:1: most of it is agreement grey.
    let grey = count(AGREE);
    assert!(grey > 50_000, "overlay not visible: {grey} grey pixels");
    assert!(count(TABLE_HEADER) > 2_000, "tables not visible");
    // A blank or broken page has a handful of colours; this one has plots and text.
    let distinct: std::collections::HashSet<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 200, "page looks blank");
    println!("screenshot: {}", shot.display());
}
