//! Generates `tagsplat.h` from `src/` with cbindgen and holds the committed
//! `include/tagsplat.h` to it: a build whose header would differ fails, naming the command that
//! rewrites it (`TAGSPLAT_WRITE_HEADER=1`), so the header in the repository is always the ABI
//! the library exports.

use std::path::{Path, PathBuf};

/// Set to 1, the build rewrites `include/tagsplat.h` instead of failing when it differs.
const WRITE_ENV: &str = "TAGSPLAT_WRITE_HEADER";

fn main() {
    let crate_dir = PathBuf::from(env("CARGO_MANIFEST_DIR"));
    let committed = crate_dir.join("include/tagsplat.h");
    for watched in ["src", "cbindgen.toml", "include/tagsplat.h"] {
        println!("cargo:rerun-if-changed={}", crate_dir.join(watched).display());
    }
    println!("cargo:rerun-if-env-changed={WRITE_ENV}");
    let header = generate(&crate_dir);
    let generated = PathBuf::from(env("OUT_DIR")).join("tagsplat.h");
    write(&generated, &header);
    if std::fs::read_to_string(&committed).ok().as_deref() == Some(header.as_str()) {
        return;
    }
    if std::env::var(WRITE_ENV).is_ok_and(|v| v == "1") {
        write(&committed, &header);
        return;
    }
    eprintln!(
        "error: {} is not what cbindgen generates from src/ (the new one is {}).\n\
         Rewrite it with `{WRITE_ENV}=1 cargo build --profile test -p tagsplat-capi` and \
         commit it: it is the library's ABI.",
        committed.display(),
        generated.display()
    );
    std::process::exit(1);
}

/// The header text: cbindgen's output for `src/lib.rs` (and the modules it declares) with the
/// crate's version as macros.
fn generate(crate_dir: &Path) -> String {
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml"))
        .unwrap_or_else(|e| fail(&format!("cbindgen.toml: {e}")));
    let version = format!(
        "#define TAGSPLAT_VERSION_MAJOR {}\n#define TAGSPLAT_VERSION_MINOR {}\n\
         #define TAGSPLAT_VERSION_PATCH {}\n#define TAGSPLAT_VERSION_STRING \"{}\"\n",
        env("CARGO_PKG_VERSION_MAJOR"),
        env("CARGO_PKG_VERSION_MINOR"),
        env("CARGO_PKG_VERSION_PATCH"),
        env("CARGO_PKG_VERSION"),
    );
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(crate_dir.join("src/lib.rs"))
        .with_after_include(version)
        .generate()
        .unwrap_or_else(|e| fail(&format!("cbindgen: {e}")));
    let mut text = Vec::new();
    bindings.write(&mut text);
    String::from_utf8(text).unwrap_or_else(|e| fail(&format!("cbindgen wrote non-UTF-8: {e}")))
}

fn write(path: &Path, text: &str) {
    std::fs::write(path, text).unwrap_or_else(|e| fail(&format!("{}: {e}", path.display())));
}

fn env(name: &str) -> String {
    std::env::var(name).unwrap_or_else(|_| fail(&format!("{name} is not set")))
}

fn fail(message: &str) -> ! {
    eprintln!("error: {message}");
    std::process::exit(1);
}
