//! The subset of Markdown that table.md is written in, as HTML: headings, paragraphs, pipe
//! tables, list items, images, **bold**, *italic* and `code`. The report page shows table.md
//! through it, so the page and the Markdown never disagree.
use std::fmt::Write;

/// Text with `&`, `<`, `>` and `"` escaped.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            c => o.push(c),
        }
    }
    o
}

/// Inline spans: `code` first (its content is literal), then **bold** and *italic*.
fn inline(s: &str) -> String {
    let mut out = String::new();
    for (i, part) in s.split('`').enumerate() {
        if i % 2 == 1 {
            let _ = write!(out, "<code>{}</code>", escape(part));
        } else {
            out.push_str(&emphasis(&escape(part)));
        }
    }
    out
}

fn emphasis(s: &str) -> String {
    let mut out = String::new();
    for (i, part) in s.split("**").enumerate() {
        if i % 2 == 1 {
            let _ = write!(out, "<b>{part}</b>");
        } else {
            // a lone `*` between words (as in "a * b") stays; pairs make italics
            let bits: Vec<&str> = part.split('*').collect();
            if bits.len() % 2 == 1 {
                for (k, b) in bits.iter().enumerate() {
                    if k % 2 == 1 {
                        let _ = write!(out, "<i>{b}</i>");
                    } else {
                        out.push_str(b);
                    }
                }
            } else {
                out.push_str(part);
            }
        }
    }
    out
}

/// `![alt](src)` alone on a line: (alt, src).
fn image(line: &str) -> Option<(&str, &str)> {
    let rest = line.strip_prefix("![")?;
    let (alt, rest) = rest.split_once("](")?;
    let src = rest.strip_suffix(')')?;
    Some((alt, src))
}

fn cells(line: &str) -> Vec<&str> {
    let t = line.trim().trim_start_matches('|').trim_end_matches('|');
    t.split('|').map(str::trim).collect()
}

/// `md` as HTML; `images` names the class given to images.
pub fn to_html(md: &str, image_class: &str) -> String {
    let mut html = String::new();
    let lines: Vec<&str> = md.lines().collect();
    let mut i = 0;
    let mut list = false;
    while i < lines.len() {
        let line = lines[i].trim_end();
        if list && !line.starts_with("- ") {
            html.push_str("</ul>\n");
            list = false;
        }
        if line.is_empty() {
            i += 1;
            continue;
        }
        if let Some(h) = line.strip_prefix("## ") {
            let _ = writeln!(html, "<h3>{}</h3>", inline(h));
        } else if let Some(h) = line.strip_prefix("# ") {
            let _ = writeln!(html, "<h2>{}</h2>", inline(h));
        } else if let Some(item) = line.strip_prefix("- ") {
            if !list {
                html.push_str("<ul>\n");
                list = true;
            }
            let _ = writeln!(html, "<li>{}</li>", inline(item));
        } else if let Some((alt, src)) = image(line) {
            let _ = writeln!(
                html,
                "<figure><img class=\"{image_class}\" src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>",
                escape(src),
                escape(alt),
                escape(alt)
            );
        } else if line.starts_with('|') {
            html.push_str("<table>\n");
            let header = cells(line);
            html.push_str("<tr>");
            for c in &header {
                let _ = write!(html, "<th>{}</th>", inline(c));
            }
            html.push_str("</tr>\n");
            i += 1;
            // the |---|---:| line
            if i < lines.len() && lines[i].starts_with("|-") {
                i += 1;
            }
            while i < lines.len() && lines[i].starts_with('|') {
                html.push_str("<tr>");
                for c in cells(lines[i]) {
                    let _ = write!(html, "<td>{}</td>", inline(c));
                }
                html.push_str("</tr>\n");
                i += 1;
            }
            html.push_str("</table>\n");
            continue;
        } else {
            // a paragraph runs to the next blank line
            let mut text = line.to_string();
            while i + 1 < lines.len()
                && !lines[i + 1].trim().is_empty()
                && !lines[i + 1].starts_with(['#', '|', '!', '-'])
            {
                i += 1;
                text.push(' ');
                text.push_str(lines[i].trim());
            }
            let _ = writeln!(html, "<p>{}</p>", inline(&text));
        }
        i += 1;
    }
    if list {
        html.push_str("</ul>\n");
    }
    html
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_headings_images_and_spans() {
        let md = "# Experiment `q`\n\nA **bold** *it* <x> & `a<b`.\n\n## relMSE\n\n\
                  | scene | E&K (baseline) |\n|---|---:|\n| s | **1e-2** (1.00×) |\n\n\
                  ![s: plot](plots/s.png)\n\n- skipped a: b\n- c\n";
        let h = to_html(md, "px");
        assert!(h.contains("<h2>Experiment <code>q</code></h2>"), "{h}");
        assert!(
            h.contains("<p>A <b>bold</b> <i>it</i> &lt;x&gt; &amp; <code>a&lt;b</code>.</p>"),
            "{h}"
        );
        assert!(
            h.contains("<tr><th>scene</th><th>E&amp;K (baseline)</th></tr>"),
            "{h}"
        );
        assert!(
            h.contains("<tr><td>s</td><td><b>1e-2</b> (1.00×)</td></tr>"),
            "{h}"
        );
        assert!(h.contains("<img class=\"px\" src=\"plots/s.png\" alt=\"s: plot\">"));
        assert!(
            h.contains("<ul>\n<li>skipped a: b</li>\n<li>c</li>\n</ul>"),
            "{h}"
        );
        assert!(!h.contains("---"), "{h}");
    }
}
