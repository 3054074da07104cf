//! Test harness: a GPU context with the Khronos validation layer (synchronization validation
//! included) switched on. Dropping a [`TestGpu`] destroys the context and fails the test on any
//! validation message, those sent during destruction (leaked objects) included.

#![allow(dead_code)] // Each test binary uses its own part of the harness.

use std::path::Path;
use std::sync::Arc;
use tagsplat::gpu::{ContextOptions, GpuContext, ValidationLog};

pub struct TestGpu {
    ctx: Option<Arc<GpuContext>>,
    log: Arc<ValidationLog>,
}

/// A validated context on the device the environment picks (lavapipe on CI).
pub fn gpu() -> TestGpu {
    gpu_with(ContextOptions::default())
}

/// [`gpu`] with other options (validation stays on).
pub fn gpu_with(options: ContextOptions) -> TestGpu {
    let options = ContextOptions { validation: Some(true), ..options };
    let ctx =
        GpuContext::new(&options).unwrap_or_else(|e| panic!("cannot create a Vulkan context: {e}"));
    let log = ctx.validation().clone();
    TestGpu { ctx: Some(ctx), log }
}

impl TestGpu {
    pub fn ctx(&self) -> &Arc<GpuContext> {
        self.ctx.as_ref().expect("context lives until drop")
    }
}

impl Drop for TestGpu {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        // Destroy the context now, so messages about leaked objects are counted too.
        let ctx = self.ctx.take().expect("dropped once");
        assert!(
            Arc::try_unwrap(ctx).is_ok(),
            "the GPU context is still referenced at the end of the test"
        );
        let messages = self.log.messages();
        assert!(
            messages.is_empty(),
            "{} validation message(s):\n{}",
            messages.len(),
            messages.join("\n")
        );
    }
}

/// Deterministic test data.
pub fn rng(seed: u64) -> tagsplat::rng::SplitMix64 {
    tagsplat::rng::SplitMix64::new(seed)
}

/// Says loudly that a check was skipped because its oracle is missing, and fails when that is
/// not allowed: in CI (`CI=true`), where the setup script must have installed every oracle.
pub fn skipped(what: &str, why: &str) {
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("{what} is required in CI (CI=true) but unavailable: {why}");
    }
    // Straight to the process's stderr: libtest's capture hides eprintln! of passing tests.
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "\n******** SKIPPED {what}: {why} ********\n");
}

/// A JSON report without what differs between two runs of the same job: times (keys ending in
/// `_s` or `_ms`), peak memory (keys starting with `peak_`), the output paths and the frames
/// found complete on disk.
pub fn without_run_specifics(value: serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    match value {
        Value::Object(map) => Value::Object(
            map.into_iter()
                .filter(|(key, _)| {
                    !(key.ends_with("_s") || key.ends_with("_ms") || key.starts_with("peak_"))
                        && key != "outputs"
                        && key != "resumed_frames"
                })
                .map(|(key, v)| (key, without_run_specifics(v)))
                .collect(),
        ),
        Value::Array(items) => Value::Array(items.into_iter().map(without_run_specifics).collect()),
        other => other,
    }
}

/// Every file under `dir`, relative to it, sorted.
pub fn file_names(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut names = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(folder) = stack.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                names.push(path.strip_prefix(dir).unwrap().to_owned());
            }
        }
    }
    names.sort();
    names
}

/// Runs the Khronos glTF validator on `path` when it is installed (scripts/setup.sh); without
/// it the check says SKIPPED, and fails in CI.
pub fn validate_gltf(path: &Path) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let installed =
        root.join(".tools/gltf-validator/node_modules/gltf-validator/package.json").is_file();
    let node = std::process::Command::new("node")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !(installed && node) {
        let why = if node {
            "gltf-validator is not installed (run scripts/setup.sh)"
        } else {
            "node is not on PATH"
        };
        skipped(&format!("the Khronos glTF validator on {}", path.display()), why);
        return;
    }
    let out = std::process::Command::new("node")
        .arg(root.join("scripts/validate_gltf.cjs"))
        .arg(path)
        .output()
        .unwrap();
    let report = String::from_utf8_lossy(&out.stdout);
    eprintln!("glTF validator: {report}");
    assert!(
        out.status.success(),
        "the glTF validator rejects {}: {report}{}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_str(report.trim()).unwrap();
    assert_eq!((json["errors"].as_u64(), json["warnings"].as_u64()), (Some(0), Some(0)));
}
