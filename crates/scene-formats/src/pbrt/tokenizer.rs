//! pbrt's lexical syntax, read as a stream: bare words (directives, `true`/`false`), quoted
//! strings, numbers, `[` and `]`; `#` starts a comment to the end of the line. Numbers are
//! parsed as they are read, so a file of hundreds of MB of mesh text is never held as text:
//! only a 256 KiB read buffer and the current token are.
use std::io::{BufRead, ErrorKind};

#[derive(Clone, Debug, PartialEq)]
pub enum Token {
    Word(String),
    Str(String),
    Num(f64),
    Open,
    Close,
}

impl Token {
    /// How the token reads in an error message.
    pub fn describe(&self) -> String {
        match self {
            Token::Word(w) => format!("`{w}`"),
            Token::Str(s) => format!("\"{s}\""),
            Token::Num(x) => format!("{x}"),
            Token::Open => "`[`".into(),
            Token::Close => "`]`".into(),
        }
    }
}

/// A lexical error, with the line it happened on.
#[derive(Debug)]
pub struct LexError {
    pub line: usize,
    pub message: String,
}

pub struct Tokenizer<R> {
    reader: R,
    line: usize,
    peeked: Option<(Token, usize)>,
    scratch: Vec<u8>,
}

impl<R: BufRead> Tokenizer<R> {
    pub fn new(reader: R) -> Self {
        Tokenizer {
            reader,
            line: 1,
            peeked: None,
            scratch: Vec::new(),
        }
    }

    /// The line the reader is on (where the next token starts or the file ended).
    pub fn line(&self) -> usize {
        self.peeked.as_ref().map_or(self.line, |p| p.1)
    }

    fn err(&self, line: usize, message: impl Into<String>) -> LexError {
        LexError {
            line,
            message: message.into(),
        }
    }

    fn peek_byte(&mut self) -> Result<Option<u8>, LexError> {
        loop {
            match self.reader.fill_buf() {
                Ok(buf) => return Ok(buf.first().copied()),
                Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                Err(e) => return Err(self.err(self.line, format!("read error: {e}"))),
            }
        }
    }

    fn bump(&mut self) {
        self.reader.consume(1);
    }

    /// The next token and the line it starts on, or `None` at the end of the file.
    pub fn peek(&mut self) -> Result<Option<&(Token, usize)>, LexError> {
        if self.peeked.is_none() {
            self.peeked = self.read()?;
        }
        Ok(self.peeked.as_ref())
    }

    pub fn next(&mut self) -> Result<Option<(Token, usize)>, LexError> {
        match self.peeked.take() {
            Some(t) => Ok(Some(t)),
            None => self.read(),
        }
    }

    fn read(&mut self) -> Result<Option<(Token, usize)>, LexError> {
        // skip white space and comments
        loop {
            match self.peek_byte()? {
                None => return Ok(None),
                Some(b'\n') => {
                    self.line += 1;
                    self.bump();
                }
                Some(b' ' | b'\t' | b'\r' | 0x0b | 0x0c) => self.bump(),
                Some(b'#') => {
                    while let Some(c) = self.peek_byte()? {
                        if c == b'\n' {
                            break;
                        }
                        self.bump();
                    }
                }
                Some(_) => break,
            }
        }
        let line = self.line;
        let c = self.peek_byte()?.expect("a byte was peeked");
        let token = match c {
            b'[' => {
                self.bump();
                Token::Open
            }
            b']' => {
                self.bump();
                Token::Close
            }
            b'"' => {
                self.bump();
                Token::Str(self.string(line)?)
            }
            b'0'..=b'9' | b'-' | b'+' | b'.' => {
                self.scratch.clear();
                while let Some(c) = self.peek_byte()? {
                    if c.is_ascii_alphanumeric() || matches!(c, b'-' | b'+' | b'.') {
                        self.scratch.push(c);
                        self.bump();
                    } else {
                        break;
                    }
                }
                let text = std::str::from_utf8(&self.scratch).unwrap_or("?");
                match text.parse::<f64>() {
                    Ok(x) => Token::Num(x),
                    Err(_) => return Err(self.err(line, format!("malformed number `{text}`"))),
                }
            }
            c if c.is_ascii_alphabetic() || c == b'_' => {
                self.scratch.clear();
                while let Some(c) = self.peek_byte()? {
                    if c.is_ascii_alphanumeric() || c == b'_' {
                        self.scratch.push(c);
                        self.bump();
                    } else {
                        break;
                    }
                }
                Token::Word(String::from_utf8_lossy(&self.scratch).into_owned())
            }
            c => {
                return Err(self.err(
                    line,
                    format!("unexpected character `{}`", char::from(c).escape_default()),
                ));
            }
        };
        Ok(Some((token, line)))
    }

    /// The rest of a quoted string (the opening quote is consumed). pbrt's escapes are
    /// honoured; a newline or the end of the file before the closing quote is an error.
    fn string(&mut self, line: usize) -> Result<String, LexError> {
        self.scratch.clear();
        loop {
            match self.peek_byte()? {
                None | Some(b'\n') => return Err(self.err(line, "unterminated string")),
                Some(b'"') => {
                    self.bump();
                    break;
                }
                Some(b'\\') => {
                    self.bump();
                    let e = match self.peek_byte()? {
                        None | Some(b'\n') => return Err(self.err(line, "unterminated string")),
                        Some(b'n') => b'\n',
                        Some(b't') => b'\t',
                        Some(b'r') => b'\r',
                        Some(b'b') => 8,
                        Some(b'f') => 12,
                        Some(c) => c,
                    };
                    self.bump();
                    self.scratch.push(e);
                }
                Some(c) => {
                    self.scratch.push(c);
                    self.bump();
                }
            }
        }
        String::from_utf8(std::mem::take(&mut self.scratch))
            .map_err(|_| self.err(line, "string is not UTF-8"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tokens(text: &str) -> Result<Vec<(Token, usize)>, LexError> {
        // a tiny buffer, so tokens straddle buffer refills
        let mut t = Tokenizer::new(std::io::BufReader::with_capacity(3, text.as_bytes()));
        let mut out = Vec::new();
        while let Some(tok) = t.next()? {
            out.push(tok);
        }
        Ok(out)
    }

    #[test]
    fn reads_every_kind_of_token_with_its_line() {
        let t = tokens("Shape \"sphere\" # a comment \"not a string\"\n  \"float radius\" [ -1.5e-1 .5 +2 ]\nWorldEnd").unwrap();
        let want = vec![
            (Token::Word("Shape".into()), 1),
            (Token::Str("sphere".into()), 1),
            (Token::Str("float radius".into()), 2),
            (Token::Open, 2),
            (Token::Num(-0.15), 2),
            (Token::Num(0.5), 2),
            (Token::Num(2.0), 2),
            (Token::Close, 2),
            (Token::Word("WorldEnd".into()), 3),
        ];
        assert_eq!(t, want);
        assert_eq!(
            tokens("\"a\\\"b\\n\"").unwrap()[0].0,
            Token::Str("a\"b\n".into())
        );
    }

    #[test]
    fn malformed_input_names_its_line() {
        for (text, line, what) in [
            ("Shape\n\"sphere", 2, "unterminated string"),
            ("Shape \"sph\nere\"", 1, "unterminated string"),
            ("\n\nTranslate 1 2..3 4", 3, "malformed number"),
            ("Film {", 1, "unexpected character"),
        ] {
            let e = tokens(text).unwrap_err();
            assert_eq!(e.line, line, "{text}");
            assert!(e.message.contains(what), "{}", e.message);
        }
    }
}
