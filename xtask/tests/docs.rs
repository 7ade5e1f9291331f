//! The documentation stays a guide: the README short and free of commit hashes, ARCHITECTURE.md
//! short with its invariants, every relative link resolving inside the repository, and the
//! dependency invariants ARCHITECTURE.md states true of the crates' manifests.
use std::path::{Path, PathBuf};

const README_MAX_LINES: usize = 300;
const ARCHITECTURE_MAX_LINES: usize = 200;

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the repository root")
        .to_path_buf()
}

fn read(rel: &str) -> String {
    let path = repo_root().join(rel);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
}

/// Tokens that look like abbreviated or full git commit hashes: 7 to 40 lowercase hex digits
/// with at least one digit and one letter, bounded by non-word characters.
fn commit_hashes(text: &str) -> Vec<&str> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|t| {
            (7..=40).contains(&t.len())
                && t.bytes()
                    .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
                && t.bytes().any(|b| b.is_ascii_digit())
                && t.bytes().any(|b| b.is_ascii_alphabetic())
        })
        .collect()
}

/// The text outside fenced code blocks and inline code spans, where Markdown makes links.
fn prose(text: &str) -> String {
    let mut out = String::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        // Even-numbered pieces between backticks are outside code spans.
        for (i, piece) in line.split('`').enumerate() {
            if i % 2 == 0 {
                out.push_str(piece);
            }
        }
        out.push('\n');
    }
    out
}

/// The targets of inline links and images, `[text](target "title")`, and of `<img src="…">`.
fn link_targets(text: &str) -> Vec<String> {
    let text = prose(text);
    let mut targets = Vec::new();
    let mut rest = text.as_str();
    while let Some(i) = rest.find("](") {
        rest = &rest[i + 2..];
        let end = rest.find([')', '\n']).unwrap_or(rest.len());
        let inner = rest[..end].trim();
        let target = inner.split_whitespace().next().unwrap_or("");
        targets.push(target.trim_matches(['<', '>']).to_string());
    }
    let mut rest = text.as_str();
    while let Some(i) = rest.find("<img src=\"") {
        rest = &rest[i + "<img src=\"".len()..];
        if let Some(end) = rest.find('"') {
            targets.push(rest[..end].to_string());
        }
    }
    targets
}

/// The repository-relative path a link in `file` points to, or `None` for links that leave the
/// repository's files (web, mail) or stay on the page (`#anchor`).
fn local_path(file: &Path, target: &str) -> Option<PathBuf> {
    let lower = target.to_ascii_lowercase();
    if target.is_empty()
        || target.starts_with('#')
        || lower.starts_with("http://")
        || lower.starts_with("https://")
        || lower.starts_with("mailto:")
    {
        return None;
    }
    let path = target.split(['#', '?']).next().unwrap_or(target);
    Some(file.parent().unwrap_or(Path::new("")).join(path))
}

fn markdown_files_under(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            markdown_files_under(&path, out);
        } else if path.extension().is_some_and(|e| e == "md") {
            out.push(path);
        }
    }
}

/// README.md, ARCHITECTURE.md, xtask/README.md and every Markdown file under docs/, relative to
/// the repository root.
fn checked_pages() -> Vec<PathBuf> {
    let root = repo_root();
    let mut pages: Vec<PathBuf> = ["README.md", "ARCHITECTURE.md", "xtask/README.md"]
        .iter()
        .map(PathBuf::from)
        .collect();
    let mut docs = Vec::new();
    markdown_files_under(&root.join("docs"), &mut docs);
    docs.sort();
    pages.extend(
        docs.iter()
            .map(|p| p.strip_prefix(&root).unwrap().to_path_buf()),
    );
    pages
}

#[test]
fn readme_is_short_and_names_no_commit() {
    let readme = read("README.md");
    let lines = readme.lines().count();
    assert!(
        lines <= README_MAX_LINES,
        "README.md has {lines} lines, more than {README_MAX_LINES}: move detail to docs/"
    );
    let hashes = commit_hashes(&readme);
    assert!(
        hashes.is_empty(),
        "README.md names commits {hashes:?}: dated figures belong in docs/notes/"
    );
}

#[test]
fn architecture_is_short_and_states_its_invariants() {
    let text = read("ARCHITECTURE.md");
    let lines = text.lines().count();
    assert!(
        lines <= ARCHITECTURE_MAX_LINES,
        "ARCHITECTURE.md has {lines} lines, more than {ARCHITECTURE_MAX_LINES}"
    );
    assert!(
        text.lines().any(|l| l.trim_end() == "## Invariants"),
        "ARCHITECTURE.md has no `## Invariants` section"
    );
}

#[test]
fn every_relative_link_resolves() {
    let root = repo_root();
    let mut missing = Vec::new();
    let mut checked = 0;
    for page in checked_pages() {
        for target in link_targets(&read(page.to_str().unwrap())) {
            if let Some(path) = local_path(&page, &target) {
                checked += 1;
                if !root.join(&path).exists() {
                    missing.push(format!("{}: {target}", page.display()));
                }
            }
        }
    }
    assert!(
        checked > 0,
        "no relative link found: is the link parser broken?"
    );
    assert!(
        missing.is_empty(),
        "links to missing files:\n{}",
        missing.join("\n")
    );
}

/// The `[dependencies]` of a workspace crate, by name.
fn dependencies(krate: &str) -> Vec<String> {
    let manifest: toml::Table = read(&format!("crates/{krate}/Cargo.toml"))
        .parse()
        .unwrap_or_else(|e| panic!("crates/{krate}/Cargo.toml: {e}"));
    manifest
        .get("dependencies")
        .and_then(|d| d.as_table())
        .map(|d| d.keys().cloned().collect())
        .unwrap_or_default()
}

#[test]
fn crates_depend_the_way_architecture_says() {
    for leaf in ["light-tree", "brdf-integrals", "pixel-samples"] {
        let deps = dependencies(leaf);
        for scene_crate in ["render-core", "scene-formats", "samplers"] {
            assert!(
                !deps.iter().any(|d| d == scene_crate),
                "{leaf} depends on {scene_crate}: it must never see a scene"
            );
        }
    }
    let core = dependencies("render-core");
    for upper in ["samplers", "scene-formats", "manylights"] {
        assert!(
            !core.iter().any(|d| d == upper),
            "render-core depends on {upper}: dependencies point one way"
        );
    }
}

#[test]
fn the_checks_see_what_they_look_for() {
    assert_eq!(
        commit_hashes("at eec4dfc, and 1.19e-4 or deadbeef"),
        ["eec4dfc"]
    );
    assert!(commit_hashes("1234567 and abcdefa and the 2026-12-05 run").is_empty());
    let links = link_targets(
        "[a](docs/x.md#part) ![b](p.png \"t\") `[c](not/a/link)` <img src=\"i.png\" width=\"40%\">\n```\n[d](code)\n```\n",
    );
    assert_eq!(links, ["docs/x.md#part", "p.png", "i.png"]);
    let page = Path::new("docs/README.md");
    assert_eq!(local_path(page, "https://example.org/a.md"), None);
    assert_eq!(local_path(page, "#anchor"), None);
    assert_eq!(
        local_path(page, "notes/x.md#y"),
        Some(PathBuf::from("docs/notes/x.md"))
    );
}
