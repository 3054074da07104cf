//! Data flows one way between the engine's top-level modules: a module may use a module below it,
//! never one that (through others) uses it back. The test reads `engine/` and fails with the
//! cycle and the files that close it. References count from non-comment lines outside
//! `#[cfg(test)]` modules (tests may reach across).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Graph = BTreeMap<String, BTreeMap<String, BTreeSet<PathBuf>>>;

fn rust_files(path: &Path, out: &mut Vec<PathBuf>) {
    files_ending(path, "rs", out);
}

/// Every file under `path` (or `path` itself) whose extension is `extension`.
fn files_ending(path: &Path, extension: &str, out: &mut Vec<PathBuf>) {
    if path.is_dir() {
        for entry in std::fs::read_dir(path).unwrap() {
            files_ending(&entry.unwrap().path(), extension, out);
        }
    } else if path.is_file() && path.extension().is_some_and(|e| e == extension) {
        out.push(path.to_owned());
    }
}

/// The modules named by `crate::NAME` in `source`, code lines before the first test module.
fn crate_references(source: &str) -> BTreeSet<String> {
    let code = source.split("#[cfg(test)]").next().unwrap_or("");
    let mut names = BTreeSet::new();
    for line in code.lines().filter(|l| !l.trim_start().starts_with("//")) {
        for (at, _) in line.match_indices("crate::") {
            let rest = &line[at + "crate::".len()..];
            let name: String =
                rest.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
            names.insert(name);
        }
    }
    names
}

/// module → module it uses → the files that use it.
fn module_graph(engine: &Path) -> Graph {
    let modules: BTreeSet<String> = std::fs::read_dir(engine)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name() != Some("lib.rs".as_ref()))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    let mut graph = Graph::new();
    for module in &modules {
        let mut files = Vec::new();
        rust_files(&engine.join(module), &mut files);
        rust_files(&engine.join(format!("{module}.rs")), &mut files);
        let uses = graph.entry(module.clone()).or_default();
        for file in files {
            let source = std::fs::read_to_string(&file).unwrap();
            for name in crate_references(&source) {
                if &name != module && modules.contains(&name) {
                    uses.entry(name).or_default().insert(file.clone());
                }
            }
        }
    }
    graph
}

/// A cycle through `graph` as a list of modules (first repeated last), if there is one.
fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &Graph,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|n| n == node) {
            let mut cycle = path[at..].to_vec();
            cycle.push(node.to_owned());
            return Some(cycle);
        }
        if done.contains(node) {
            return None;
        }
        path.push(node.to_owned());
        for next in graph.get(node).into_iter().flat_map(|uses| uses.keys()) {
            if let Some(cycle) = visit(next, graph, path, done) {
                return Some(cycle);
            }
        }
        path.pop();
        done.insert(node.to_owned());
        None
    }
    let mut done = BTreeSet::new();
    graph.keys().find_map(|start| visit(start, graph, &mut Vec::new(), &mut done))
}

#[test]
fn engine_modules_depend_on_each_other_without_cycles() {
    let graph = module_graph(&Path::new(env!("CARGO_MANIFEST_DIR")).join("engine"));
    assert!(graph.len() > 20 && graph["score"].contains_key("track"), "{graph:?}");
    if let Some(cycle) = find_cycle(&graph) {
        let edges: Vec<String> = cycle
            .windows(2)
            .map(|pair| format!("{} -> {} in {:?}", pair[0], pair[1], graph[&pair[0]][&pair[1]]))
            .collect();
        panic!("module cycle {}:\n{}", cycle.join(" -> "), edges.join("\n"));
    }
}

#[test]
fn a_cycle_is_found_and_comments_do_not_count() {
    let source = "use crate::b::X;\n// crate::c in a comment\nfn f() { crate::d::g(); }\n#[cfg(test)]\nmod tests { use crate::e; }";
    let names: Vec<String> = crate_references(source).into_iter().collect();
    assert_eq!(names, ["b", "d"]);
    let edge = |to: &str| (to.to_owned(), BTreeSet::new());
    let mut graph = Graph::new();
    graph.insert("a".into(), [edge("b")].into());
    graph.insert("b".into(), [edge("c")].into());
    graph.insert("c".into(), BTreeMap::new());
    assert_eq!(find_cycle(&graph), None);
    graph.get_mut("c").unwrap().insert("a".into(), BTreeSet::new());
    assert_eq!(find_cycle(&graph).unwrap(), ["a", "b", "c", "a"]);
}

/// Every `docs/NAME.md` that the code or the README cites is in the repository.
#[test]
fn cited_documents_exist() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![root.join("README.md")];
    rust_files(&root.join("engine"), &mut files);
    rust_files(&root.join("tools"), &mut files);
    let mut cited = BTreeSet::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        for (at, _) in text.match_indices("docs/") {
            let name: String = text[at..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || "/_.-".contains(*c))
                .collect();
            if let Some(name) =
                name.strip_suffix('.').or(Some(&name)).filter(|n| n.ends_with(".md"))
            {
                cited.insert((name.to_owned(), file.clone()));
            }
        }
    }
    assert!(cited.iter().any(|(name, _)| name == "docs/conventions.md"), "{cited:?}");
    let missing: Vec<_> = cited.iter().filter(|(name, _)| !root.join(name).is_file()).collect();
    assert!(missing.is_empty(), "cited but not in the repository: {missing:?}");
}

/// A fresh clone is all a reader has: no code, test, script or document points at the team's
/// shared folder or at the planning documents that live outside the repository.
#[test]
fn nothing_cites_files_outside_the_repository() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![root.join("README.md")];
    for (folder, extension) in [("docs", "md"), ("scripts", "sh"), ("scripts", "py")] {
        files_ending(&root.join(folder), extension, &mut files);
    }
    for folder in ["engine", "tools", "tests", "examples", "benches"] {
        rust_files(&root.join(folder), &mut files);
    }
    // Spelled in pieces so that this file does not cite them itself.
    let outside =
        [["..", "/shared"], ["ARCHITECTURE", ".md"], ["CONVENTIONS", ".md"], ["MISSION", ".md"]]
            .map(|pieces| pieces.concat());
    let mut found = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        for (n, line) in text.lines().enumerate() {
            if let Some(name) = outside.iter().find(|name| line.contains(name.as_str())) {
                found.push(format!("{}:{}: {name}", file.display(), n + 1));
            }
        }
    }
    assert!(files.len() > 100, "{} files scanned", files.len());
    assert!(found.is_empty(), "cites files outside the repository:\n{}", found.join("\n"));
}

/// Every shader with push constants has a Rust struct checked against its block at compile
/// time: its constant is named in a `push_layout!` invocation somewhere in the engine.
#[test]
fn every_push_constant_block_has_a_push_layout() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    rust_files(&root.join("engine"), &mut files);
    let mut listed = BTreeSet::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        for (at, _) in text.match_indices("push_layout!(") {
            let invocation = text[at..].split(");").next().unwrap_or("");
            let words = invocation.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'));
            listed.extend(words.map(str::to_owned));
        }
    }
    let shaders = tagsplat::shaders::ALL;
    assert!(shaders.len() > 30, "{} shaders", shaders.len());
    let unchecked: Vec<&str> = shaders
        .iter()
        .filter(|(name, shader)| shader.push_size > 0 && !listed.contains(*name))
        .map(|(name, _)| *name)
        .collect();
    let with_push = shaders.iter().filter(|(_, shader)| shader.push_size > 0).count();
    assert!(with_push > 20, "{with_push} shaders with push constants");
    assert!(unchecked.is_empty(), "push constants without push_layout!: {unchecked:?}");
}
