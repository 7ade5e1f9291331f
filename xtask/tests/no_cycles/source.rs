//! Rust source as far as modules go: tokens, `mod` declarations, `use` trees and paths.

/// A token of Rust source with its line; comments, numbers and literals other than strings
/// are dropped.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Tok {
    Ident(String),
    Str(String),
    PathSep,
    Punct(char),
}

pub(crate) fn tokenize(src: &str) -> Vec<(Tok, usize)> {
    let c: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line) = (0, 1);
    while i < c.len() {
        let ch = c[i];
        let start = i;
        if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && c.get(i + 1) == Some(&'*') {
            i = block_comment_end(&c, i);
        } else if let Some(end) = raw_string_end(&c, i) {
            out.push((Tok::Str(c[i..end].iter().collect()), line));
            i = end;
        } else if ch == '"' || (ch == 'b' && c.get(i + 1) == Some(&'"')) {
            let body = i + if ch == 'b' { 2 } else { 1 };
            let close = string_close(&c, body);
            out.push((Tok::Str(c[body..close].iter().collect()), line));
            i = close + 1;
        } else if ch == '\'' {
            i = char_or_lifetime_end(&c, i);
        } else if ch.is_alphanumeric() || ch == '_' {
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            if !ch.is_ascii_digit() {
                out.push((Tok::Ident(c[start..i].iter().collect()), line));
            }
        } else if ch == ':' && c.get(i + 1) == Some(&':') {
            out.push((Tok::PathSep, line));
            i += 2;
        } else {
            out.push((Tok::Punct(ch), line));
            i += 1;
        }
        i = i.min(c.len());
        line += c[start..i].iter().filter(|&&ch| ch == '\n').count();
    }
    out
}

/// Where the (nestable) block comment starting at `i` ends.
fn block_comment_end(c: &[char], mut i: usize) -> usize {
    let mut depth = 0;
    while i < c.len() {
        if c[i] == '/' && c.get(i + 1) == Some(&'*') {
            depth += 1;
            i += 2;
        } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
            depth -= 1;
            i += 2;
            if depth == 0 {
                break;
            }
        } else {
            i += 1;
        }
    }
    i
}

/// The closing quote of the string whose body starts at `i` (the end of the text if none).
fn string_close(c: &[char], mut i: usize) -> usize {
    while i < c.len() && c[i] != '"' {
        i += if c[i] == '\\' { 2 } else { 1 };
    }
    i.min(c.len())
}

/// Past a char literal ('x', '\n', '\u{..}') or a lifetime's quote ('a) at `i`.
fn char_or_lifetime_end(c: &[char], i: usize) -> usize {
    if c.get(i + 1) == Some(&'\\') {
        let mut j = i + 2;
        while j < c.len() && c[j] != '\'' {
            j += 1;
        }
        j + 1
    } else if c.get(i + 2) == Some(&'\'') {
        i + 3
    } else {
        i + 1
    }
}

/// Where a raw string (`r"…"`, `r#"…"#`, `br"…"`) starting at `i` ends.
pub(crate) fn raw_string_end(c: &[char], i: usize) -> Option<usize> {
    let mut j = i;
    if c.get(j) == Some(&'b') {
        j += 1;
    }
    if c.get(j) != Some(&'r') || (i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_')) {
        return None;
    }
    j += 1;
    let hashes = c[j..].iter().take_while(|&&h| h == '#').count();
    j += hashes;
    if c.get(j) != Some(&'"') {
        return None;
    }
    j += 1;
    while j < c.len() {
        if c[j] == '"'
            && c[j + 1..]
                .iter()
                .take(hashes)
                .filter(|&&h| h == '#')
                .count()
                == hashes
        {
            return Some(j + 1 + hashes);
        }
        j += 1;
    }
    Some(c.len())
}

/// A module path from the crate root (`["experiments", "viewer"]`).
pub(crate) type ModPath = Vec<String>;

/// What one file says about modules.
#[derive(Default)]
pub(crate) struct FileScan {
    /// `mod name;` declarations: module path, whether under `#[cfg(test)]`, `#[path]`.
    pub(crate) declared: Vec<(ModPath, bool, Option<String>)>,
    /// Inline modules (`mod name { … }`) and whether they are test code.
    pub(crate) inline: Vec<(ModPath, bool)>,
    /// Paths named: the module they are written in, the path, its line, and whether it is a
    /// re-export (`pub use`), with the name it is exported as.
    pub(crate) paths: Vec<PathUse>,
}

pub(crate) struct PathUse {
    pub(crate) scope: ModPath,
    pub(crate) segments: Vec<String>,
    pub(crate) line: usize,
    pub(crate) reexport_as: Option<String>,
}

pub(crate) fn scan(tokens: &[(Tok, usize)], module: &ModPath) -> FileScan {
    let mut s = Scanner {
        tokens,
        out: FileScan::default(),
        scopes: vec![(module.clone(), 0)],
        depth: 0,
        attrs: Vec::new(),
        public: false,
    };
    let mut i = 0;
    while i < tokens.len() {
        i = s.step(i);
    }
    s.out
}

/// A walk over a file's tokens that keeps what [`FileScan`] needs.
struct Scanner<'a> {
    tokens: &'a [(Tok, usize)],
    out: FileScan,
    /// The modules open at this point: path and the brace depth that closes each.
    scopes: Vec<(ModPath, usize)>,
    depth: usize,
    /// The attributes (`#[…]`) before the item at hand.
    attrs: Vec<Vec<Tok>>,
    /// Whether the item at hand is `pub`.
    public: bool,
}

impl Scanner<'_> {
    fn ident(&self, k: usize) -> Option<&str> {
        match self.tokens.get(k) {
            Some((Tok::Ident(w), _)) => Some(w.as_str()),
            _ => None,
        }
    }

    fn punct(&self, k: usize, p: char) -> bool {
        matches!(self.tokens.get(k), Some((Tok::Punct(q), _)) if *q == p)
    }

    fn scope(&self) -> ModPath {
        self.scopes.last().unwrap().0.clone()
    }

    /// Reads what starts at token `i`; returns where the next thing starts.
    fn step(&mut self, i: usize) -> usize {
        let inner = self.punct(i + 1, '!') && self.punct(i + 2, '[');
        if self.punct(i, '#') && (self.punct(i + 1, '[') || inner) {
            let open = if self.punct(i + 1, '[') { i + 1 } else { i + 2 };
            let close = matching(self.tokens, open, '[', ']');
            let attr = self.tokens[open + 1..close].iter().map(|t| t.0.clone());
            self.attrs.push(attr.collect());
            return close + 1;
        }
        let next = match &self.tokens[i].0 {
            Tok::Punct('{') => {
                self.depth += 1;
                i + 1
            }
            Tok::Punct('}') => {
                if self.scopes.len() > 1 && self.scopes.last().unwrap().1 == self.depth {
                    self.scopes.pop();
                }
                self.depth = self.depth.saturating_sub(1);
                i + 1
            }
            Tok::Ident(w) if w == "pub" => {
                self.public = true;
                return if self.punct(i + 1, '(') {
                    matching(self.tokens, i + 1, '(', ')') + 1
                } else {
                    i + 1
                };
            }
            Tok::Ident(w) if w == "mod" && self.ident(i + 1).is_some() => self.module(i),
            Tok::Ident(w) if w == "use" => self.use_tree(i),
            Tok::Ident(_) if matches!(self.tokens.get(i + 1), Some((Tok::PathSep, _))) => {
                self.path(i)
            }
            _ => i + 1,
        };
        self.attrs.clear();
        self.public = false;
        next
    }

    /// `mod name;` or `mod name {`.
    fn module(&mut self, i: usize) -> usize {
        let mut path = self.scope();
        path.push(self.ident(i + 1).unwrap().to_string());
        let test = self.attrs.iter().any(|a| is_cfg_test(a));
        if self.punct(i + 2, ';') {
            let path_attr = path_attr(&self.attrs);
            self.out.declared.push((path, test, path_attr));
        } else {
            self.depth += 1;
            self.out.inline.push((path.clone(), test));
            self.scopes.push((path, self.depth));
        }
        i + 3
    }

    /// A `use` declaration, one path per leaf of its tree.
    fn use_tree(&mut self, i: usize) -> usize {
        let end = (i..self.tokens.len())
            .find(|&k| self.punct(k, ';'))
            .unwrap_or(self.tokens.len());
        for (segments, alias) in expand_use(&self.tokens[i + 1..end]) {
            let reexport_as = self
                .public
                .then(|| alias.unwrap_or(segments.last().unwrap().clone()));
            self.out.paths.push(PathUse {
                scope: self.scope(),
                segments,
                line: self.tokens[i].1,
                reexport_as,
            });
        }
        end + 1
    }

    /// A path in code (`a::b::c`), kept unless it continues another (`<T as X>::a::b`).
    fn path(&mut self, i: usize) -> usize {
        let after_sep = i > 0 && matches!(self.tokens[i - 1].0, Tok::PathSep);
        let mut segments = vec![self.ident(i).unwrap().to_string()];
        let mut k = i + 1;
        while matches!(self.tokens.get(k), Some((Tok::PathSep, _))) {
            match self.ident(k + 1) {
                Some(next) => segments.push(next.to_string()),
                None => break,
            }
            k += 2;
        }
        if !after_sep {
            self.out.paths.push(PathUse {
                scope: self.scope(),
                segments,
                line: self.tokens[i].1,
                reexport_as: None,
            });
        }
        k
    }
}

/// Index of the bracket closing the one at `open`.
pub(crate) fn matching(tokens: &[(Tok, usize)], open: usize, o: char, c: char) -> usize {
    let mut depth = 0;
    for (k, (t, _)) in tokens.iter().enumerate().skip(open) {
        if *t == Tok::Punct(o) {
            depth += 1;
        } else if *t == Tok::Punct(c) {
            depth -= 1;
            if depth == 0 {
                return k;
            }
        }
    }
    tokens.len() - 1
}

pub(crate) fn is_cfg_test(attr: &[Tok]) -> bool {
    let has = |w: &str| attr.iter().any(|t| *t == Tok::Ident(w.into()));
    attr.first() == Some(&Tok::Ident("cfg".into())) && has("test") && !has("not")
}

pub(crate) fn path_attr(attrs: &[Vec<Tok>]) -> Option<String> {
    attrs.iter().find_map(|a| match a.as_slice() {
        [Tok::Ident(p), Tok::Punct('='), Tok::Str(s)] if p == "path" => Some(s.clone()),
        _ => None,
    })
}

/// The paths of a use tree (`a::{b, c::{self, D as E}}`), each with its `as` name.
pub(crate) fn expand_use(tokens: &[(Tok, usize)]) -> Vec<(Vec<String>, Option<String>)> {
    let toks: Vec<&Tok> = tokens.iter().map(|t| &t.0).collect();
    let mut out = Vec::new();
    expand_tree(&toks, &mut 0, Vec::new(), &mut out);
    out
}

pub(crate) fn expand_tree(
    toks: &[&Tok],
    i: &mut usize,
    mut prefix: Vec<String>,
    out: &mut Vec<(Vec<String>, Option<String>)>,
) {
    if matches!(toks.get(*i), Some(Tok::PathSep)) {
        *i += 1;
    }
    loop {
        match toks.get(*i) {
            Some(Tok::Ident(w)) if w == "self" && !prefix.is_empty() => {
                *i += 1;
            }
            Some(Tok::Ident(w)) if w == "as" => {
                *i += 1;
                if let Some(Tok::Ident(alias)) = toks.get(*i) {
                    *i += 1;
                    out.push((prefix, Some(alias.clone())));
                }
                return;
            }
            Some(Tok::Ident(w)) => {
                prefix.push(w.clone());
                *i += 1;
            }
            Some(Tok::Punct('*')) => {
                *i += 1;
                out.push((prefix, Some("*".into())));
                return;
            }
            Some(Tok::Punct('{')) => {
                *i += 1;
                while !matches!(toks.get(*i), Some(Tok::Punct('}')) | None) {
                    expand_tree(toks, i, prefix.clone(), out);
                    if matches!(toks.get(*i), Some(Tok::Punct(','))) {
                        *i += 1;
                    }
                }
                *i += 1;
                return;
            }
            _ => {
                if !prefix.is_empty() {
                    out.push((prefix, None));
                }
                return;
            }
        }
        if matches!(toks.get(*i), Some(Tok::PathSep)) {
            *i += 1;
        }
    }
}
