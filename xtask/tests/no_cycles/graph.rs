//! The files of a crate as a graph, and its circles.
use super::source::{FileScan, ModPath, PathUse, scan, tokenize};
use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// The files of one crate root and which depends on which.
pub(crate) struct Graph {
    /// Files relative to the crate's folder; an inline test module is `file.rs::path`.
    pub(crate) nodes: Vec<String>,
    /// from -> to -> (line, path as written) of the first mention.
    pub(crate) edges: BTreeMap<usize, BTreeMap<usize, (usize, String)>>,
}

/// Module path -> the node its code belongs to, and whether it is test code.
type Modules = BTreeMap<ModPath, (usize, bool)>;

/// A crate root's module tree: its modules, the node names, each file's scan.
#[derive(Default)]
struct Tree {
    modules: Modules,
    nodes: Vec<String>,
    scans: Vec<FileScan>,
}

/// A module file still to read: its path, module path, whether test code, and whether its
/// children live beside it (`lib.rs`, `main.rs`, `mod.rs`) rather than in a folder of its name.
type Pending = (PathBuf, ModPath, bool, bool);

impl Tree {
    /// Walks the module tree from `root`, one file at a time, in declaration order.
    fn walk(dir: &Path, root: &Path) -> Tree {
        let mut tree = Tree::default();
        let mut todo: Vec<Pending> = vec![(root.to_path_buf(), ModPath::new(), false, true)];
        let mut next = 0;
        while let Some((file, module, test, owns_dir)) = todo.get(next).cloned() {
            next += 1;
            let Ok(src) = fs::read_to_string(dir.join(&file)) else {
                continue;
            };
            let test = test || file.file_name().is_some_and(|f| f == "tests.rs");
            let s = scan(&tokenize(&src), &module);
            tree.add_file(&file, &module, test, &s);
            for decl in &s.declared {
                todo.push(tree.child(dir, (&file, owns_dir), &module, test, decl));
            }
            tree.scans.push(s);
        }
        tree
    }

    /// A file's node, and its inline modules: test ones as nodes of their own.
    fn add_file(&mut self, file: &Path, module: &ModPath, test: bool, s: &FileScan) {
        let name = file.to_string_lossy().replace('\\', "/");
        self.modules
            .insert(module.clone(), (self.nodes.len(), test));
        self.nodes.push(name.clone());
        for (path, inline_test) in &s.inline {
            let (parent, parent_test) = self.modules[&path[..path.len() - 1]];
            if *inline_test && !test {
                let sub = path[module.len()..].join("::");
                self.modules.insert(path.clone(), (self.nodes.len(), true));
                self.nodes.push(format!("{name}::{sub}"));
            } else {
                self.modules
                    .insert(path.clone(), (parent, test || parent_test));
            }
        }
    }

    /// Where the module declared by `decl` in `file` lives.
    fn child(
        &self,
        dir: &Path,
        (file, owns_dir): (&Path, bool),
        module: &ModPath,
        test: bool,
        (path, child_test, path_attr): &(ModPath, bool, Option<String>),
    ) -> Pending {
        // Children of `a/b.rs` live in `a/b/`; of `lib.rs`, `main.rs`, `mod.rs` beside them.
        let mut folder = if owns_dir {
            file.parent().unwrap().to_path_buf()
        } else {
            file.with_extension("")
        };
        for m in &path[module.len()..path.len() - 1] {
            folder.push(m);
        }
        let leaf = path.last().unwrap();
        let parent_test = self
            .modules
            .get(&path[..path.len() - 1])
            .is_some_and(|m| m.1);
        let (child, owns) = match path_attr {
            Some(p) => (file.parent().unwrap().join(p), p.ends_with("mod.rs")),
            None if dir.join(folder.join(format!("{leaf}.rs"))).is_file() => {
                (folder.join(format!("{leaf}.rs")), false)
            }
            None => (folder.join(leaf).join("mod.rs"), true),
        };
        (
            child,
            path.clone(),
            test || *child_test || parent_test,
            owns,
        )
    }
}

impl Graph {
    pub(crate) fn of_crate(dir: &Path, root: &Path) -> Graph {
        let tree = Tree::walk(dir, root);
        let reexports = Reexports::of(&tree.scans, &tree.modules);
        let mut g = Graph {
            nodes: tree.nodes.clone(),
            edges: BTreeMap::new(),
        };
        for p in tree.scans.iter().flat_map(|s| &s.paths) {
            if p.reexport_as.is_none() {
                g.add_edge(p, &tree.modules, &reexports);
            }
        }
        g
    }

    /// The edge a path makes, if any.
    fn add_edge(&mut self, p: &PathUse, modules: &Modules, reexports: &Reexports) {
        let from = modules[&p.scope].0;
        let Some(abs) = absolute(&p.scope, &p.segments, modules) else {
            return;
        };
        let to_module = reexports.resolve(&abs, modules, 0);
        let to = modules[&to_module].0;
        // A module and its submodules are one unit: a parent composes its children, the
        // children see the parent's items.
        let nested = p.scope.starts_with(&to_module) || to_module.starts_with(&p.scope);
        if to != from && !nested {
            self.edges
                .entry(from)
                .or_default()
                .entry(to)
                .or_insert((p.line, p.segments.join("::")));
        }
    }

    /// The strongly connected parts of two or more files (Tarjan's algorithm).
    pub(crate) fn circles(&self) -> Vec<Vec<usize>> {
        struct State<'a> {
            g: &'a Graph,
            index: Vec<Option<usize>>,
            low: Vec<usize>,
            on_stack: Vec<bool>,
            stack: Vec<usize>,
            next: usize,
            parts: Vec<Vec<usize>>,
        }
        fn visit(s: &mut State, v: usize) {
            s.index[v] = Some(s.next);
            s.low[v] = s.next;
            s.next += 1;
            s.stack.push(v);
            s.on_stack[v] = true;
            let targets: Vec<usize> =
                s.g.edges
                    .get(&v)
                    .map(|e| e.keys().copied().collect())
                    .unwrap_or_default();
            for w in targets {
                match s.index[w] {
                    None => {
                        visit(s, w);
                        s.low[v] = s.low[v].min(s.low[w]);
                    }
                    Some(iw) if s.on_stack[w] => s.low[v] = s.low[v].min(iw),
                    _ => {}
                }
            }
            if Some(s.low[v]) == s.index[v] {
                let mut part = Vec::new();
                while let Some(w) = s.stack.pop() {
                    s.on_stack[w] = false;
                    part.push(w);
                    if w == v {
                        break;
                    }
                }
                if part.len() > 1 {
                    part.sort();
                    s.parts.push(part);
                }
            }
        }
        let n = self.nodes.len();
        let mut s = State {
            g: self,
            index: vec![None; n],
            low: vec![0; n],
            on_stack: vec![false; n],
            stack: Vec::new(),
            next: 0,
            parts: Vec::new(),
        };
        for v in 0..n {
            if s.index[v].is_none() {
                visit(&mut s, v);
            }
        }
        s.parts.sort();
        s.parts
    }

    /// Every elementary circle of a strongly connected part (at most 50), each with the
    /// lines that make its edges.
    pub(crate) fn describe(&self, part: &[usize]) -> String {
        let inside: BTreeSet<usize> = part.iter().copied().collect();
        let mut cycles = Vec::new();
        for &start in part {
            // Circles through `start` and larger nodes only, so each is listed once.
            let mut path = vec![start];
            self.circles_from(start, &inside, &mut path, &mut cycles);
        }
        let mut lines = Vec::new();
        for cycle in cycles.iter().take(50) {
            let names: Vec<&str> = cycle.iter().map(|&n| self.nodes[n].as_str()).collect();
            let why: Vec<String> = cycle
                .iter()
                .zip(cycle.iter().skip(1))
                .map(|(a, b)| {
                    let (line, path) = &self.edges[a][b];
                    format!("{}:{line} `{path}`", self.nodes[*a])
                })
                .collect();
            lines.push(format!("{} ({})", names.join(" -> "), why.join(", ")));
        }
        if cycles.len() > 50 {
            lines.push(format!("… and {} more circles", cycles.len() - 50));
        }
        lines.join("\n    ")
    }

    pub(crate) fn circles_from(
        &self,
        start: usize,
        inside: &BTreeSet<usize>,
        path: &mut Vec<usize>,
        out: &mut Vec<Vec<usize>>,
    ) {
        if out.len() > 50 {
            return;
        }
        let last = *path.last().unwrap();
        for &next in self
            .edges
            .get(&last)
            .map(|e| e.keys())
            .into_iter()
            .flatten()
        {
            if next == start {
                let mut c = path.clone();
                c.push(start);
                out.push(c);
            } else if next > start && inside.contains(&next) && !path.contains(&next) {
                path.push(next);
                self.circles_from(start, inside, path, out);
                path.pop();
            }
        }
    }
}

/// The path's module-path form from the crate root, or `None` for another crate's item.
pub(crate) fn absolute(
    scope: &ModPath,
    segments: &[String],
    modules: &Modules,
) -> Option<Vec<String>> {
    let first = segments.first()?.as_str();
    let mut at = match first {
        "crate" => ModPath::new(),
        "self" | "super" => scope.clone(),
        _ => {
            let mut child = scope.clone();
            child.push(first.to_string());
            if !modules.contains_key(&child) {
                return None;
            }
            scope.clone()
        }
    };
    let mut rest = &segments[usize::from(first == "crate" || first == "self")..];
    while rest.first().is_some_and(|s| s == "super") {
        at.pop();
        rest = &rest[1..];
    }
    at.extend(rest.iter().cloned());
    Some(at)
}

/// The crate's re-exports: module -> exported name -> the absolute path it stands for.
pub(crate) struct Reexports(BTreeMap<ModPath, BTreeMap<String, Vec<String>>>);

impl Reexports {
    fn of(scans: &[FileScan], modules: &Modules) -> Reexports {
        let mut map: BTreeMap<ModPath, BTreeMap<String, Vec<String>>> = BTreeMap::new();
        for s in scans {
            for p in &s.paths {
                let (Some(name), Some(abs)) =
                    (&p.reexport_as, absolute(&p.scope, &p.segments, modules))
                else {
                    continue;
                };
                map.entry(p.scope.clone())
                    .or_default()
                    .insert(name.clone(), abs);
            }
        }
        Reexports(map)
    }

    /// The module whose file defines what `path` names: the deepest module on the path, or,
    /// when the item after it is a re-export, the module it comes from.
    fn resolve(&self, path: &[String], modules: &Modules, depth: usize) -> ModPath {
        let mut at = ModPath::new();
        for seg in path {
            let mut next = at.clone();
            next.push(seg.clone());
            if !modules.contains_key(&next) {
                break;
            }
            at = next;
        }
        let item = path.get(at.len());
        let target = item.and_then(|name| self.0.get(&at)?.get(name));
        match target {
            Some(t) if depth < 8 => {
                let mut followed = t.clone();
                followed.extend(path[at.len() + 1..].iter().cloned());
                self.resolve(&followed, modules, depth + 1)
            }
            _ => at,
        }
    }
}
