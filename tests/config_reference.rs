//! Keeps docs/configuration.md true: its `## train` and `## fit` tables list exactly the keys
//! `tagsplat train --print-config` and `tagsplat fit --print-config` print, each under the
//! `### [section]` heading of its TOML section (`### top level` outside any), with the printed
//! default text and a meaning. No GPU: it serializes the defaults as the CLI does
//! (`TrainConfig::to_toml`, `FitConfig::to_toml`) and reads the markdown.

use std::collections::{BTreeMap, BTreeSet};
use tagsplat::train::pipeline::TrainConfig;
use tagsplat::train::FitConfig;

const DOC: &str = "docs/configuration.md";

/// One documented key: its default and meaning as written, and the heading it sits under.
struct Row {
    default: String,
    meaning: String,
    heading: String,
}

/// Runs of whitespace as one space, trimmed.
fn normalize(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The printed TOML's leaves as (dotted key, value text exactly as printed), in print order.
/// Checked against a real TOML parse of the same text, so a layout this reader does not know
/// (a multi-line array, an inline table) fails loudly instead of hiding a key.
fn printed_values(toml_text: &str) -> Vec<(String, String)> {
    let mut section = String::new();
    let mut values = Vec::new();
    for (n, line) in toml_text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if let Some(name) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            section = name.trim().to_owned();
            continue;
        }
        let (key, value) = line
            .split_once('=')
            .unwrap_or_else(|| panic!("printed config line {}: no `key = value`: {line}", n + 1));
        let key = key.trim();
        let dotted = if section.is_empty() { key.to_owned() } else { format!("{section}.{key}") };
        values.push((dotted, normalize(value)));
    }

    let table: toml::Table = toml::from_str(toml_text).expect("the printed config parses");
    let mut leaves = BTreeSet::new();
    collect_leaves(&table, "", &mut leaves);
    let read: BTreeSet<String> = values.iter().map(|(k, _)| k.clone()).collect();
    assert_eq!(read, leaves, "the line reader and the TOML parser disagree on the printed keys");
    assert_eq!(read.len(), values.len(), "a printed key appears twice");
    values
}

/// Dotted paths of every non-table value under `table`.
fn collect_leaves(table: &toml::Table, prefix: &str, out: &mut BTreeSet<String>) {
    for (key, value) in table {
        let path = if prefix.is_empty() { key.clone() } else { format!("{prefix}.{key}") };
        match value {
            toml::Value::Table(inner) => collect_leaves(inner, &path, out),
            _ => {
                out.insert(path);
            }
        }
    }
}

/// The table rows of the `## {config}` part of the reference, by key; panics naming a row
/// that is not `| `key` | `default` | meaning |` or a key documented twice.
fn documented(doc: &str, config: &str) -> BTreeMap<String, Row> {
    let wanted = format!("## {config}");
    let mut inside = false;
    let mut heading = String::new();
    let mut rows = BTreeMap::new();
    for (n, line) in doc.lines().enumerate() {
        let line = line.trim();
        if line.starts_with("## ") {
            inside = line == wanted;
            continue;
        }
        if !inside {
            continue;
        }
        if let Some(h) = line.strip_prefix("### ") {
            heading = h.trim().to_owned();
            continue;
        }
        if !line.starts_with('|') {
            continue;
        }
        let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
        // The header and the separator row.
        if cells.first().is_some_and(|c| *c == "key" || c.chars().all(|ch| ch == '-' || ch == ':'))
        {
            continue;
        }
        let where_ = format!("{DOC}:{}", n + 1);
        assert!(cells.len() >= 3, "{where_}: a row needs key, default and meaning: {line}");
        let code = |cell: &str, what: &str| -> String {
            cell.strip_prefix('`')
                .and_then(|c| c.strip_suffix('`'))
                .unwrap_or_else(|| panic!("{where_}: the {what} `{cell}` is not in backticks"))
                .to_owned()
        };
        let key = code(cells[0], "key");
        let row = Row {
            default: normalize(&code(cells[1], "default")),
            // A `|` inside a meaning would split it: keep the rest of the row together.
            meaning: cells[2..].join("|").trim().to_owned(),
            heading: heading.clone(),
        };
        if rows.insert(key.clone(), row).is_some() {
            panic!("{where_}: `{key}` is documented twice under ## {config}");
        }
    }
    assert!(!rows.is_empty(), "{DOC} has no `{wanted}` table rows");
    rows
}

/// The heading a key belongs under: `[section]` of its TOML section, `top level` outside any.
fn expected_heading(key: &str) -> String {
    match key.rsplit_once('.') {
        Some((section, _)) => format!("[{section}]"),
        None => "top level".to_owned(),
    }
}

/// Every disagreement between the printed defaults and the documented ones, as lines.
fn problems(config: &str, printed_toml: &str, doc: &str) -> Vec<String> {
    let printed = printed_values(printed_toml);
    let rows = documented(doc, config);
    let printed_keys: BTreeSet<&str> = printed.iter().map(|(k, _)| k.as_str()).collect();
    let documented_keys: BTreeSet<&str> = rows.keys().map(String::as_str).collect();
    let mut problems = Vec::new();
    for key in printed_keys.difference(&documented_keys) {
        problems.push(format!("## {config}: `{key}` is printed but not documented (missing)"));
    }
    for key in documented_keys.difference(&printed_keys) {
        problems.push(format!("## {config}: `{key}` is documented but not printed (extra)"));
    }
    for (key, value) in &printed {
        let Some(row) = rows.get(key) else { continue };
        if row.default != *value {
            problems.push(format!(
                "## {config}: `{key}` documents default `{}`, --print-config prints `{value}`",
                row.default
            ));
        }
        if row.meaning.is_empty() {
            problems.push(format!("## {config}: `{key}` has no meaning"));
        }
        let heading = expected_heading(key);
        if row.heading != heading {
            problems.push(format!(
                "## {config}: `{key}` sits under `### {}`, belongs under `### {heading}`",
                row.heading
            ));
        }
    }
    problems
}

fn reference() -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(DOC);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn reference_lists_every_printed_key_with_its_default() {
    let doc = reference();
    let mut all = problems("train", &TrainConfig::default().to_toml(), &doc);
    all.extend(problems("fit", &FitConfig::default().to_toml(), &doc));
    assert!(all.is_empty(), "{DOC} is out of date:\n{}", all.join("\n"));
}

#[test]
fn the_check_catches_a_wrong_default_a_missing_key_and_an_extra_one() {
    let printed = "seed = 0\nlevels = [2, 1]\n\n[a.b]\nrest = \"previous\"\n";
    let doc = "## train\n\n### top level\n\n| key | default | meaning |\n|---|---|---|\n\
               | `seed` | `1` | Seeds. |\n| `bogus` | `3` | Not a key. |\n\n\
               ### [a.b]\n\n| key | default | meaning |\n|---|---|---|\n\
               | `a.b.rest` | `\"previous\"` |  |\n\n## fit\n";
    let found = problems("train", printed, doc);
    let expect = [
        "`levels` is printed but not documented (missing)",
        "`bogus` is documented but not printed (extra)",
        "`seed` documents default `1`, --print-config prints `0`",
        "`a.b.rest` has no meaning",
    ];
    for e in expect {
        assert!(found.iter().any(|p| p.contains(e)), "no `{e}` in {found:#?}");
    }
    assert_eq!(found.len(), expect.len(), "{found:#?}");
}
