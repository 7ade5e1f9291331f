//! No file of a crate depends, through a chain of others, on itself.
//!
//! For every crate of the workspace (`crates/*` and `xtask`), and for each of its crate roots
//! (library, binaries, integration tests, benches, examples), the source files form a graph: a
//! file depends on the module files named by its `use crate::…`, `use super::…`, `use child::…`
//! and by `crate::…`, `super::…`, `child::…` paths in its code. What is not an edge:
//! - a `mod child;` declaration (the parent owns the child; it does not use it);
//! - a path between a module and its own submodules, either way (`use super::Params` in a
//!   child, `child::build()` in its parent): a module and what it contains are one unit, as
//!   Rust's privacy has it, so a circle is one between files neither of which holds the other
//!   (siblings and cousins, like `a.rs` and `b.rs` that import from each other);
//! - a re-export (`pub use child::X`): the parent is only a doorway, and a path through it
//!   (`crate::X`) is followed to the file that defines `X`;
//! - what a test module (`#[cfg(test)] mod tests`, inline or in its own file) uses: test code
//!   is a node of its own, so it adds no edge to the file that holds it;
//! - paths in comments, doc links and strings.
//!
//! The test fails listing every circle of two or more files, with the lines that close it.
mod graph;
mod source;

use graph::Graph;
use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

/// Circles known and broken elsewhere, as the set of files of their strongly connected part
/// (the test also fails once one of them is gone, so that the list only holds live ones).
const ALLOWED: &[(&str, &[&str])] = &[];

#[test]
fn no_module_circles_in_the_workspace() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut crates: Vec<PathBuf> = fs::read_dir(root.join("crates"))
        .expect("the workspace's crates/ folder")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("Cargo.toml").is_file())
        .collect();
    crates.sort();
    crates.push(root.join("xtask"));
    let mut report = Vec::new();
    let mut allowed_seen = vec![false; ALLOWED.len()];
    let mut files_seen = 0;
    for dir in &crates {
        let name = dir.file_name().unwrap().to_string_lossy().into_owned();
        for crate_root in crate_roots(dir) {
            let graph = Graph::of_crate(dir, &crate_root);
            files_seen += graph.nodes.len();
            for part in graph.circles() {
                let files: BTreeSet<&str> = part.iter().map(|&n| graph.nodes[n].as_str()).collect();
                let allowed = ALLOWED.iter().position(|(c, f)| {
                    *c == name && f.iter().copied().collect::<BTreeSet<_>>() == files
                });
                if let Some(k) = allowed {
                    allowed_seen[k] = true;
                } else {
                    report.push(format!("{name}: {}", graph.describe(&part)));
                }
            }
        }
    }
    assert!(files_seen > 100, "only {files_seen} source files found");
    for (seen, (c, files)) in allowed_seen.iter().zip(ALLOWED) {
        assert!(
            seen,
            "{c}: {files:?} is no circle any more: take it off ALLOWED"
        );
    }
    assert!(
        report.is_empty(),
        "module circles (break them with a leaf module both sides import):\n{}",
        report.join("\n")
    );
}

/// The checker on a small crate of its own: it finds the one circle there is, follows a
/// re-export to the file behind it, and skips comments, strings, nesting and tests.
#[test]
fn the_checker_finds_a_circle_and_ignores_what_is_not_one() {
    let dir = std::env::temp_dir().join(format!("no-cycles-{}", std::process::id()));
    let write = |path: &str, text: &str| {
        let p = dir.join(path);
        fs::create_dir_all(p.parent().unwrap()).unwrap();
        fs::write(p, text).unwrap();
    };
    write(
        "src/lib.rs",
        "mod a;\nmod b;\nmod c;\nmod d;\nmod e;\n#[cfg(test)]\nmod tests;\npub use c::C;\n\
         pub struct Root;\nfn f() { let _ = c::C; }\n",
    );
    // a <-> b: a names b in its code, b imports a.
    write(
        "src/a.rs",
        "pub struct A;\nfn f() -> crate::b::B { todo!() }\n",
    );
    write("src/b.rs", "use crate::{Root, a::A};\npub struct B;\n");
    // c -> e only in a comment and a string; its inline tests use d.
    write(
        "src/c.rs",
        "use super::Root;\npub struct C;\n// crate::e::E\nconst S: &str = \"crate::e::E\";\n\
         #[cfg(test)]\nmod tests {\n    use super::*;\n    use crate::d::D;\n}\n",
    );
    // d reaches c through the root's re-export; e uses d.
    write("src/d.rs", "pub struct D(crate::C);\n");
    write("src/e.rs", "use crate::d::D;\npub struct E;\n");
    write("src/tests.rs", "use super::*;\nuse crate::e::E;\n");
    let graph = Graph::of_crate(&dir, Path::new("src/lib.rs"));
    let circles: Vec<String> = graph.circles().iter().map(|p| graph.describe(p)).collect();
    let node = |name: &str| graph.nodes.iter().position(|n| n == name).unwrap();
    let edge = |a: &str, b: &str| {
        graph
            .edges
            .get(&node(a))
            .is_some_and(|e| e.contains_key(&node(b)))
    };
    fs::remove_dir_all(&dir).unwrap();
    assert_eq!(circles.len(), 1, "{circles:?}");
    assert!(
        circles[0].starts_with("src/a.rs -> src/b.rs -> src/a.rs"),
        "{}",
        circles[0]
    );
    assert!(
        circles[0].contains("src/a.rs:2 `crate::b::B`"),
        "{}",
        circles[0]
    );
    assert!(edge("src/d.rs", "src/c.rs") && edge("src/e.rs", "src/d.rs"));
    assert!(edge("src/c.rs::tests", "src/d.rs") && edge("src/tests.rs", "src/e.rs"));
    assert!(!edge("src/c.rs", "src/e.rs") && !edge("src/c.rs", "src/d.rs"));
    assert!(!edge("src/d.rs", "src/lib.rs") && !edge("src/lib.rs", "src/c.rs"));
}

/// The files that start a module tree of the crate in `dir`, relative to it.
fn crate_roots(dir: &Path) -> Vec<PathBuf> {
    let mut roots = Vec::new();
    for f in ["src/lib.rs", "src/main.rs"] {
        if dir.join(f).is_file() {
            roots.push(PathBuf::from(f));
        }
    }
    for sub in ["src/bin", "tests", "benches", "examples"] {
        let Ok(entries) = fs::read_dir(dir.join(sub)) else {
            continue;
        };
        let mut found: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter_map(|p| {
                let rel = Path::new(sub).join(p.file_name()?);
                if p.extension().is_some_and(|e| e == "rs") {
                    Some(rel)
                } else if p.join("main.rs").is_file() {
                    Some(rel.join("main.rs"))
                } else {
                    None
                }
            })
            .collect();
        found.sort();
        roots.extend(found);
    }
    roots
}
