//! The parser's input: the include stack (`Include`, `Import`), tokens of the current file,
//! directive arguments (strings, numbers, parameter lists), and messages with file and line.
use super::Parser;
use super::records::Source;
use crate::pbrt::params::{Param, ParamList, Values};
use crate::pbrt::tokenizer::{LexError, Token, Tokenizer};
use render_core::error::SceneError;
use std::fs::File;
use std::io::BufReader;
use std::path::Path;

impl Parser<'_> {
    /// `Include` and `Import` (the same here: a file read in place).
    pub(super) fn include(&mut self, d: &str, line: usize) -> Result<(), SceneError> {
        let name = self.string_arg(d, line)?;
        self.open(Path::new(&name), Some(line))
    }

    // ---- errors, warnings and positions -------------------------------------------------

    /// The current file, as messages show it.
    pub(super) fn current_file(&self) -> String {
        self.sources.last().map_or("?", |s| s.shown.as_str()).into()
    }

    /// `file:line` of the current file.
    pub(super) fn here(&self, line: usize) -> String {
        format!("{}:{line}", self.current_file())
    }

    /// An error at `line` of the current file.
    pub(super) fn err(&self, line: usize, message: impl Into<String>) -> SceneError {
        SceneError::Pbrt {
            path: self
                .sources
                .last()
                .map_or_else(|| "?".into(), |s| s.shown.clone()),
            line,
            message: message.into(),
        }
    }

    /// A warning at `line`; a message given before is counted, not repeated.
    pub(super) fn warn(&mut self, line: usize, message: impl Into<String>) {
        let message = message.into();
        let at = self.here(line);
        match self.warnings.iter_mut().find(|w| w.0 == message) {
            Some(w) => w.2 += 1,
            None => self.warnings.push((message, at, 1)),
        }
    }

    // ---- sources -----------------------------------------------------------------------

    /// Opens a file (relative paths: to the main file's directory, as pbrt resolves them).
    pub(super) fn open(&mut self, name: &Path, line: Option<usize>) -> Result<(), SceneError> {
        let path = if name.is_absolute() || self.sources.is_empty() {
            name.to_path_buf()
        } else {
            self.base_dir.join(name)
        };
        // An included file is named after the including file's line; the main file is named
        // once, by the `Io` error itself.
        let fail = |this: &Self, what: &str, detail: String| match line {
            Some(l) => this.err(l, format!("{what}{}: {detail}", path.display())),
            None => SceneError::Io {
                path: path.display().to_string(),
                message: detail,
            },
        };
        if path.extension().is_some_and(|e| e == "gz") {
            let detail = "gzip-compressed files are not supported (gunzip it first)";
            return Err(fail(self, "", detail.into()));
        }
        let file = File::open(&path).map_err(|e| fail(self, "cannot open ", e.to_string()))?;
        let canonical = path.canonicalize().unwrap_or_else(|_| path.clone());
        if let Some(k) = self.sources.iter().position(|s| s.canonical == canonical) {
            let chain: Vec<&str> = self.sources[k..].iter().map(|s| s.shown.as_str()).collect();
            let cycle = format!("Include cycle: {} → {}", chain.join(" → "), path.display());
            return Err(self.err(line.unwrap_or(0), cycle));
        }
        self.sources.push(Source {
            tokens: Tokenizer::new(BufReader::with_capacity(1 << 18, file)),
            shown: path.display().to_string(),
            canonical,
        });
        Ok(())
    }

    fn lex_err(&self, e: LexError) -> SceneError {
        self.err(e.line, e.message)
    }

    /// The next token of the current file (a directive's arguments never span files).
    pub(super) fn next_in_file(&mut self) -> Result<Option<(Token, usize)>, SceneError> {
        let src = self.sources.last_mut().expect("a source is open");
        src.tokens.next().map_err(|e| {
            let e2 = LexError {
                line: e.line,
                message: e.message,
            };
            self.lex_err(e2)
        })
    }

    /// The next token of the current file, left in place.
    pub(super) fn peek_in_file(&mut self) -> Result<Option<Token>, SceneError> {
        let src = self.sources.last_mut().expect("a source is open");
        match src.tokens.peek() {
            Ok(t) => Ok(t.map(|t| t.0.clone())),
            Err(e) => Err(self.lex_err(e)),
        }
    }

    /// Whether a string (a parameter declaration) comes next.
    pub(super) fn peek_is_str(&mut self) -> Result<bool, SceneError> {
        let src = self.sources.last_mut().expect("a source is open");
        match src.tokens.peek() {
            Ok(t) => Ok(matches!(t, Some((Token::Str(_), _)))),
            Err(e) => Err(self.lex_err(e)),
        }
    }

    /// The current file's last line read.
    pub(super) fn eof_line(&self) -> usize {
        self.sources.last().map_or(0, |s| s.tokens.line())
    }

    /// A quoted-string argument of `directive`.
    pub(super) fn string_arg(
        &mut self,
        directive: &str,
        line: usize,
    ) -> Result<String, SceneError> {
        match self.next_in_file()? {
            Some((Token::Str(s), _)) => Ok(s),
            Some((t, l)) => Err(self.err(
                l,
                format!(
                    "{directive} expects a quoted string, found {}",
                    t.describe()
                ),
            )),
            None => Err(self.err(line, format!("{directive}: unexpected end of file"))),
        }
    }

    /// `n` numbers, bare or in one pair of brackets.
    pub(super) fn numbers(
        &mut self,
        directive: &str,
        n: usize,
        line: usize,
    ) -> Result<Vec<f64>, SceneError> {
        let bracketed = matches!(self.peek_in_file()?, Some(Token::Open));
        if bracketed {
            self.next_in_file()?;
        }
        let mut v = Vec::with_capacity(n);
        while v.len() < n {
            match self.next_in_file()? {
                Some((Token::Num(x), _)) => v.push(x),
                Some((t, l)) => {
                    return Err(self.err(
                        l,
                        format!("{directive} expects {n} numbers, found {}", t.describe()),
                    ));
                }
                None => return Err(self.err(line, format!("{directive}: unexpected end of file"))),
            }
        }
        if bracketed {
            match self.next_in_file()? {
                Some((Token::Close, _)) => {}
                Some((t, l)) => {
                    return Err(self.err(
                        l,
                        format!(
                            "{directive} expects {n} numbers then `]`, found {}",
                            t.describe()
                        ),
                    ));
                }
                None => return Err(self.err(line, format!("{directive}: unexpected end of file"))),
            }
        }
        Ok(v)
    }

    /// A parameter list: `"type name" value` or `"type name" [ values ]`, repeated.
    pub(super) fn params(&mut self) -> Result<ParamList, SceneError> {
        let mut list = ParamList::default();
        while self.peek_is_str()? {
            let Some((Token::Str(decl), line)) = self.next_in_file()? else {
                unreachable!()
            };
            let values = match self.next_in_file()? {
                Some((Token::Open, _)) => {
                    let mut nums = Vec::new();
                    let mut strs = Vec::new();
                    let mut bools = Vec::new();
                    loop {
                        match self.next_in_file()? {
                            Some((Token::Close, _)) => break,
                            Some((Token::Num(x), _)) => nums.push(x),
                            Some((Token::Str(s), _)) => strs.push(s),
                            Some((Token::Word(w), _)) if w == "true" || w == "false" => {
                                bools.push(w == "true")
                            }
                            Some((t, l)) => {
                                return Err(self.err(
                                    l,
                                    format!(
                                        "parameter \"{decl}\": unexpected {} in its values",
                                        t.describe()
                                    ),
                                ));
                            }
                            None => {
                                return Err(self.err(line, format!("parameter \"{decl}\": `[` without `]` before the end of the file")));
                            }
                        }
                    }
                    match (nums.is_empty(), strs.is_empty(), bools.is_empty()) {
                        (_, true, true) => Values::Nums(nums),
                        (true, false, true) => Values::Strs(strs),
                        (true, true, false) => Values::Bools(bools),
                        _ => {
                            return Err(self.err(
                                line,
                                format!("parameter \"{decl}\" mixes numbers, strings and booleans"),
                            ));
                        }
                    }
                }
                Some((Token::Num(x), _)) => Values::Nums(vec![x]),
                Some((Token::Str(s), _)) => Values::Strs(vec![s]),
                Some((Token::Word(w), _)) if w == "true" || w == "false" => {
                    Values::Bools(vec![w == "true"])
                }
                Some((t, l)) => {
                    return Err(self.err(
                        l,
                        format!("parameter \"{decl}\" has no value (found {})", t.describe()),
                    ));
                }
                None => {
                    return Err(self.err(
                        line,
                        format!("parameter \"{decl}\" has no value before the end of the file"),
                    ));
                }
            };
            let p = Param::new(&decl, values, line).map_err(|m| self.err(line, m))?;
            if list.has(&p.name) {
                self.warn(
                    line,
                    format!("parameter `{}` given twice: the first is used", p.name),
                );
                continue;
            }
            list.params.push(p);
        }
        Ok(list)
    }

    /// Warns about the parameters a directive did not use.
    pub(super) fn unused(&mut self, what: &str, params: &ParamList, except: &[&str]) {
        let unused: Vec<(String, usize)> = params
            .unused()
            .filter(|p| !except.contains(&p.name.as_str()))
            .map(|p| (format!("{} {}", p.ty, p.name), p.line))
            .collect();
        for (name, line) in unused {
            self.warn(
                line,
                format!("{what}: parameter \"{name}\" is not supported (ignored)"),
            );
        }
    }
}
