//! `OUT/report.html` of a training run: one self-contained page (every image an inline PNG of
//! its view's size, every plot inline SVG, no link out of the file), rebuilt with the benchmark
//! scores by `tagsplat eval`, and drawn by headless Chromium with every image decoded and
//! something on screen (SKIPPED without `chromium`; a failure when CI=true).

mod common;

use common::{gpu, skipped};
use std::path::Path;
use std::process::Command;
use tagsplat::synth::{generate, SubjectSource, SynthOptions};
use tagsplat::train::pipeline::{run_train, TrainConfig, TrainJob};

const SIZE: u32 = 96;

#[test]
fn a_run_writes_a_self_contained_report_that_shows_its_scores_and_renders() {
    let g = gpu();
    let dir = std::env::temp_dir().join(format!("tagsplat-report-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (data, out) = (dir.join("data"), dir.join("out"));
    let options = SynthOptions {
        subject: SubjectSource::Procedural { subdivisions: 3 },
        views: 8,
        frames: 3,
        width: SIZE,
        height: SIZE,
        seed: 3,
        samples: 2,
        track_vertices: 50,
        track_surface: 50,
        ..Default::default()
    };
    generate(&options, &data).unwrap();
    let mut config = TrainConfig { sh_degree: 0, ..Default::default() };
    config.canonical.iterations = 60;
    config.temporal.iterations = 60;
    let job = TrainJob::new(&data, &out, config);
    run_train(g.ctx(), &job, &mut |_| {}).unwrap();

    // Frames 0, 1 and 2 of synth's one held-out view (of 8): target, Gaussians, mesh.
    let page = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert_eq!(check_self_contained(&page), 9);
    assert!(!page.contains("tracking RMSE"), "no scores before an evaluation");

    benchmark_ground_truth(&data);
    let eval = Command::new(env!("CARGO_BIN_EXE_tagsplat"))
        .env("TAGSPLAT_VALIDATION", "1")
        .args([
            "eval".as_ref(),
            "--pred".as_ref(),
            out.as_os_str(),
            "--gt".as_ref(),
            data.as_os_str(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&eval.stderr);
    assert!(eval.status.success() && !stderr.contains("warning"), "{stderr}");
    assert!(String::from_utf8_lossy(&eval.stdout).contains("report.html"));
    let page = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert_eq!(check_self_contained(&page), 9);
    for expected in
        ["tracking RMSE % of size", "Error per frame", "PSNR per frame", "frame 2: target"]
    {
        assert!(page.contains(expected), "{expected} missing");
    }
    assert_eq!(page.matches("<tr>").count(), 1 + 3, "a header and a row per frame");
    let scores: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("eval.json")).unwrap()).unwrap();
    for frame in scores["frames"].as_array().unwrap() {
        for key in ["tracking_rmse_over_size", "tracking_along_surface_over_size"] {
            let percent = frame[key].as_f64().unwrap() * 100.0;
            assert!(page.contains(&format!("<td>{percent:.3}</td>")), "{key} {}", frame["frame"]);
        }
    }
    println!("report.html: {} bytes", page.len());

    chromium_draws(&out.join("report.html"), &dir);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Checks that every image is an inline PNG of the views' size and every link stays inside the
/// page; returns the number of images.
fn check_self_contained(page: &str) -> usize {
    assert!(page.starts_with("<!DOCTYPE html>") && page.trim_end().ends_with("</html>"));
    assert!(
        page.contains("<svg") && page.matches("<svg").count() == page.matches("</svg>").count()
    );
    // SVG's namespace name is an identifier, never fetched.
    let text = page.replace("xmlns=\"http://www.w3.org/2000/svg\"", "");
    assert!(!text.contains("http://") && !text.contains("https://") && !text.contains("file:"));
    let links: Vec<&str> = ["src=\"", "href=\"", "url("]
        .iter()
        .flat_map(|attribute| text.split(attribute).skip(1))
        .collect();
    let mut images = 0;
    for link in links {
        let base64 = link
            .strip_prefix("data:image/png;base64,")
            .unwrap_or_else(|| panic!("a link out of the page: {}", &link[..link.len().min(80)]));
        let png = decode_base64(&base64[..base64.find('"').unwrap()]);
        let image = image::load_from_memory_with_format(&png, image::ImageFormat::Png).unwrap();
        assert_eq!((image.width(), image.height()), (SIZE, SIZE));
        images += 1;
    }
    images
}

/// The synthetic dataset's own ground truth in a benchmark's `gt/` layout.
fn benchmark_ground_truth(data: &Path) {
    let gt = data.join("gt");
    std::fs::create_dir_all(gt.join("meshes")).unwrap();
    for t in 0..3 {
        let name = format!("meshes/{t:06}.ply");
        std::fs::copy(data.join(&name), gt.join(&name)).unwrap();
    }
    std::fs::copy(data.join("points.csv"), gt.join("points.csv")).unwrap();
    std::fs::copy(data.join("trajectories.csv"), gt.join("tracks.csv")).unwrap();
    std::fs::write(gt.join("info.json"), r#"{"size": 1.0}"#).unwrap();
}

fn decode_base64(text: &str) -> Vec<u8> {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let values: Vec<u32> = text
        .trim_end_matches('=')
        .bytes()
        .map(|c| ALPHABET.iter().position(|&a| a == c).expect("a base64 character") as u32)
        .collect();
    let mut bytes = Vec::new();
    for chunk in values.chunks(4) {
        let n = chunk.iter().enumerate().fold(0, |n, (i, v)| n | v << (18 - 6 * i));
        bytes.extend((0..chunk.len() - 1).map(|k| (n >> (16 - 8 * k)) as u8));
    }
    bytes
}

/// Headless Chromium loads the page with every image decoded, and its screenshot is no blank
/// page: the renders bring thousands of colours.
fn chromium_draws(page: &Path, dir: &Path) {
    if Command::new("chromium").arg("--version").output().is_err() {
        return skipped("the headless Chromium check of report.html", "chromium not found");
    }
    // A copy that states, once loaded, how many of its images failed to decode.
    let probe = dir.join("probe.html");
    let script = "<script>addEventListener('load', () => document.body.dataset.broken = \
        [...document.images].filter(i => !i.complete || i.naturalWidth === 0).length + ' of ' + \
        document.images.length + ' images broken, ' + document.querySelectorAll('svg').length + \
        ' plots');</script>";
    let text =
        std::fs::read_to_string(page).unwrap().replace("</body>", &format!("{script}</body>"));
    std::fs::write(&probe, text).unwrap();
    let dom = chromium(&probe, &["--dump-dom"]);
    assert!(
        dom.contains("data-broken=\"0 of 9 images broken, 2 plots\""),
        "{}",
        &dom[..dom.len().min(300)]
    );

    let shot = dir.join("screenshot.png");
    chromium(page, &[&format!("--screenshot={}", shot.display()), "--window-size=1200,3000"]);
    let pixels = image::open(&shot).unwrap().to_rgb8();
    let colours: std::collections::HashSet<[u8; 3]> = pixels.pixels().map(|p| p.0).collect();
    println!("screenshot {}×{}: {} colours", pixels.width(), pixels.height(), colours.len());
    assert!(colours.len() > 1000, "{} colours: a blank page?", colours.len());
}

/// Runs headless Chromium on the file `page`; returns its stdout.
fn chromium(page: &Path, args: &[&str]) -> String {
    let url = format!("file://{}", page.canonicalize().unwrap().display());
    let output = Command::new("chromium")
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--virtual-time-budget=5000"])
        .args(args)
        .arg(&url)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "chromium {args:?}: {stderr}");
    String::from_utf8(output.stdout).unwrap()
}
