//! A report as a list of blocks (headings, paragraphs, figures with captions, key numbers,
//! tables, link lists) written both as Markdown and as one self-contained HTML page:
//! images referenced relatively, a few lines of CSS inline, no scripts, no external assets.

use std::fmt::Write as _;

/// One block of a report.
pub enum Block {
    /// Page title (one per page).
    Title(String),
    /// Section heading.
    Heading(String),
    /// A paragraph of plain text.
    Para(String),
    /// Key numbers: `(label, value, explanation)`, shown as cards in HTML.
    Keys(Vec<(String, String, String)>),
    /// An image (path relative to the page) with its caption.
    Figure { src: String, caption: String },
    /// A table: header cells, rows.
    Table { head: Vec<String>, rows: Vec<Vec<String>> },
    /// Definitions (term, meaning): what each column of a table means.
    Terms(Vec<(String, String)>),
    /// Links `(text, href)` on one line.
    Links(Vec<(String, String)>),
}

/// The page as Markdown.
pub fn markdown(blocks: &[Block]) -> String {
    let mut s = String::new();
    for b in blocks {
        let _ = match b {
            Block::Title(t) => writeln!(s, "# {t}\n"),
            Block::Heading(t) => writeln!(s, "## {t}\n"),
            Block::Para(t) => writeln!(s, "{t}\n"),
            Block::Keys(k) => {
                let rows = k.iter().map(|(l, v, e)| format!("- **{l}: {v}** — {e}"));
                writeln!(s, "{}\n", rows.collect::<Vec<_>>().join("\n"))
            }
            Block::Figure { src, caption } => writeln!(s, "![{caption}]({src})\n\n*{caption}*\n"),
            Block::Table { head, rows } => {
                let _ = writeln!(s, "| {} |", head.join(" | "));
                let _ = writeln!(s, "|{}", "---|".repeat(head.len()));
                for r in rows {
                    let _ = writeln!(s, "| {} |", r.join(" | "));
                }
                writeln!(s)
            }
            Block::Terms(t) => {
                let rows = t.iter().map(|(k, v)| format!("- **{k}**: {v}"));
                writeln!(s, "{}\n", rows.collect::<Vec<_>>().join("\n"))
            }
            Block::Links(l) => {
                let items = l.iter().map(|(t, h)| format!("[{t}]({h})"));
                writeln!(s, "{}\n", items.collect::<Vec<_>>().join(" · "))
            }
        };
    }
    s
}

/// `&`, `<`, `>`, `"` escaped for HTML text and attributes.
pub fn escape(t: &str) -> String {
    t.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

const CSS: &str = "body{font:16px/1.5 system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;\
color:#222;max-width:980px;margin:2em auto;padding:0 1.2em}\
h1{font-size:1.7em;margin-bottom:.2em}h2{margin-top:1.8em;border-bottom:1px solid #ddd}\
.keys{display:flex;flex-wrap:wrap;gap:12px;margin:1em 0}\
.key{flex:1 1 200px;border:1px solid #ddd;border-radius:8px;padding:10px 14px;background:#fafafa}\
.key b{display:block;font-size:1.45em;color:#0b5394}.key span{color:#555;font-size:.9em}\
figure{margin:1.2em 0}figure img{max-width:100%;border:1px solid #eee}\
figcaption{color:#555;font-size:.92em;margin-top:.3em}\
table{border-collapse:collapse;margin:1em 0;font-size:.92em}\
th,td{border:1px solid #ddd;padding:4px 8px;text-align:right}th{background:#f3f3f3}\
td:first-child,th:first-child{text-align:left}dt{font-weight:600}dd{margin:0 0 .5em 1.2em;color:#444}";

/// The page as self-contained HTML.
pub fn html(title: &str, blocks: &[Block]) -> String {
    let mut s = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>{}</title>\n<style>{CSS}</style></head><body>\n",
        escape(title)
    );
    let e = escape;
    for b in blocks {
        let _ = match b {
            Block::Title(t) => writeln!(s, "<h1>{}</h1>", e(t)),
            Block::Heading(t) => writeln!(s, "<h2>{}</h2>", e(t)),
            Block::Para(t) => writeln!(s, "<p>{}</p>", e(t)),
            Block::Keys(k) => {
                s.push_str("<div class=\"keys\">");
                for (l, v, x) in k {
                    let _ = write!(
                        s,
                        "<div class=\"key\">{}<b>{}</b><span>{}</span></div>",
                        e(l),
                        e(v),
                        e(x)
                    );
                }
                writeln!(s, "</div>")
            }
            Block::Figure { src, caption } => writeln!(
                s,
                "<figure><img src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>",
                e(src),
                e(caption),
                e(caption)
            ),
            Block::Table { head, rows } => {
                s.push_str("<table><tr>");
                head.iter().for_each(|h| s.push_str(&format!("<th>{}</th>", e(h))));
                s.push_str("</tr>\n");
                for r in rows {
                    s.push_str("<tr>");
                    r.iter().for_each(|c| s.push_str(&format!("<td>{}</td>", e(c))));
                    s.push_str("</tr>\n");
                }
                writeln!(s, "</table>")
            }
            Block::Terms(t) => {
                s.push_str("<dl>");
                for (k, v) in t {
                    let _ = write!(s, "<dt>{}</dt><dd>{}</dd>", e(k), e(v));
                }
                writeln!(s, "</dl>")
            }
            Block::Links(l) => {
                let items: Vec<String> =
                    l.iter().map(|(t, h)| format!("<a href=\"{}\">{}</a>", e(h), e(t))).collect();
                writeln!(s, "<p>{}</p>", items.join(" · "))
            }
        };
    }
    s.push_str("</body></html>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_forms_hold_every_block_and_html_is_escaped() {
        let blocks = vec![
            Block::Title("A <b> & c".into()),
            Block::Keys(vec![("Size".into(), "3.3 MB".into(), "instead of 20 MB".into())]),
            Block::Figure { src: "render-point.png".into(), caption: "The shirt".into() },
            Block::Table {
                head: vec!["c".into(), "error".into()],
                rows: vec![vec!["16".into(), "1.4 %".into()]],
            },
            Block::Links(vec![("details".into(), "details.html".into())]),
        ];
        let md = markdown(&blocks);
        assert!(md.starts_with("# A <b> & c\n"));
        assert!(md.contains("![The shirt](render-point.png)") && md.contains("| 16 | 1.4 % |"));
        assert!(
            md.contains("- **Size: 3.3 MB** — instead of 20 MB")
                && md.contains("[details](details.html)")
        );
        let h = html("t", &blocks);
        assert!(h.contains("<h1>A &lt;b&gt; &amp; c</h1>"));
        assert!(h.contains("<img src=\"render-point.png\"") && h.contains("<td>1.4 %</td>"));
        // Self-contained: no scripts, no absolute or remote references.
        assert!(!h.contains("<script") && !h.contains("http") && !h.contains("src=\"/"));
    }
}
