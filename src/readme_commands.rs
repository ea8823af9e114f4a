//! README.md's command lines against the real argument parser: every `btf …` synopsis in
//! README.md and docs/cli.md (inline code and `sh` blocks) is expanded into concrete command
//! lines, and each must parse with [`Cli::try_parse_from`](crate::Cli) — so a renamed flag, a
//! value a closed set does not list, or a missing required option fails this test instead of
//! a new user.
//!
//! Synopsis notation (docs/cli.md, "Reading the synopses"): `[…]` is optional, `a|b` inside a
//! word and ` | ` inside brackets are alternatives, `…` repeats, an upper-case word (`N`,
//! `DIR`, `W,C`) or `θ`/`φ` is a placeholder, a `…` standing alone is the rest of a command
//! line (its required arguments may be missing: `btf view …`). Each synopsis gives variants `k = 0, 1, …`
//! that take alternative `k` (modulo its count) everywhere, once without and once with
//! every optional part, so every alternative and every optional flag is parsed at least once.

use clap::Parser;

/// A synopsis as a tree: text, or a bracketed group of alternatives.
#[derive(Debug, Clone)]
enum Node {
    Text(String),
    Group(Vec<Vec<Node>>),
}

/// Parses `s` up to its end or an unmatched `]`; returns the alternatives and the rest.
fn parse(mut s: &str) -> (Vec<Vec<Node>>, &str) {
    let mut alts = vec![Vec::new()];
    let mut text = String::new();
    let flush = |text: &mut String, alts: &mut Vec<Vec<Node>>| {
        if !text.is_empty() {
            alts.last_mut().expect("one").push(Node::Text(std::mem::take(text)));
        }
    };
    while let Some(c) = s.chars().next() {
        if s.starts_with(" | ") {
            flush(&mut text, &mut alts);
            alts.push(Vec::new());
            s = &s[3..];
            continue;
        }
        s = &s[c.len_utf8()..];
        match c {
            '[' => {
                flush(&mut text, &mut alts);
                let (group, rest) = parse(s);
                alts.last_mut().expect("one").push(Node::Group(group));
                s = rest;
            }
            ']' => break,
            _ => text.push(c),
        }
    }
    flush(&mut text, &mut alts);
    (alts, s)
}

/// Variant `k` of a sequence (`full`: with every optional group).
fn render(seq: &[Node], k: usize, full: bool, top: bool, out: &mut String) {
    for n in seq {
        match n {
            Node::Text(t) => out.push_str(t),
            Node::Group(alts) if full || top => render(&alts[k % alts.len()], k, full, false, out),
            Node::Group(_) => {}
        }
    }
}

/// One word of a rendered synopsis: alternative `k` of `a|b|c`, placeholders as numbers.
fn word(w: &str, k: usize) -> Option<String> {
    let alts: Vec<&str> = w.split('|').collect();
    let w = alts[k % alts.len()].replace('…', "").replace("θ,φ", "30,45").replace('θ', "30");
    let placeholder = |p: &str| {
        p.chars().any(|c| c.is_ascii_uppercase())
            && p.chars().all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
    };
    let parts: Vec<&str> = w.split(',').map(|p| if placeholder(p) { "2" } else { p }).collect();
    (!w.is_empty()).then(|| parts.join(","))
}

/// The concrete command lines (without the leading `btf`) of one synopsis.
fn variants(synopsis: &str) -> Vec<Vec<String>> {
    let (alts, rest) = parse(synopsis);
    assert!(rest.is_empty(), "unbalanced ']' in `{synopsis}`");
    let n = synopsis.matches('|').count() + 1;
    let mut out: Vec<Vec<String>> = Vec::new();
    for k in 0..n {
        for full in [false, true] {
            let mut s = String::new();
            render(&[Node::Group(alts.clone())], k, full, true, &mut s);
            let v: Vec<String> = s.split_whitespace().filter_map(|w| word(w, k)).collect();
            if !out.contains(&v) {
                out.push(v);
            }
        }
    }
    out
}

/// Every `btf …` synopsis of a Markdown text: inline code spans starting with `btf ` and the
/// lines of fenced `sh` blocks starting with `btf ` (backslash continuations joined), each
/// with its 1-based line. `cargo run --release -- ARGS` counts as `btf ARGS`.
pub fn synopses(markdown: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut in_sh = None;
    let mut pending = String::new();
    let mut start = 0;
    for (i, line) in markdown.lines().enumerate() {
        let trimmed = line.trim();
        if trimmed.starts_with("```") {
            in_sh = if in_sh.is_none() { Some(trimmed == "```sh") } else { None };
            continue;
        }
        match in_sh {
            Some(true) => {
                let l = trimmed.replace("cargo run --release -- ", "btf ");
                if pending.is_empty() {
                    start = i + 1;
                }
                if let Some(cont) = l.strip_suffix('\\') {
                    pending.push_str(cont);
                    continue;
                }
                pending.push_str(&l);
                let cmd = std::mem::take(&mut pending);
                if cmd.starts_with("btf ") {
                    out.push((start, without_pipe(&cmd).to_string()));
                }
            }
            Some(false) => {}
            None => {
                let line = line.replace("\\|", "|");
                for (j, span) in line.split('`').enumerate() {
                    if j % 2 == 1 && span.starts_with("btf ") {
                        out.push((i + 1, without_pipe(span).to_string()));
                    }
                }
            }
        }
    }
    out
}

/// `s` up to a shell pipe or redirection (` | `, ` > ` outside brackets:
/// `btf inspect M.btf | head`).
fn without_pipe(s: &str) -> &str {
    let mut depth = 0i32;
    for (i, c) in s.char_indices() {
        match c {
            '[' => depth += 1,
            ']' => depth -= 1,
            '|' | '>' if depth == 0 && s[..i].ends_with(' ') && s[i + 1..].starts_with(' ') => {
                return s[..i].trim_end();
            }
            _ => {}
        }
    }
    s
}

/// Parses every variant of every synopsis of `file`; returns the failures.
fn check(file: &str, text: &str) -> (usize, Vec<String>) {
    let mut parsed = 0;
    let mut failures = Vec::new();
    for (line, synopsis) in synopses(text) {
        // A standalone `…` stands for the rest of a command line (`btf view …`): its required
        // arguments may be missing, nothing else may be wrong.
        let partial = synopsis.split_whitespace().any(|w| w == "…");
        for v in variants(&synopsis) {
            parsed += 1;
            let help = |e: &clap::Error| {
                matches!(
                    e.kind(),
                    clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion
                ) || (partial && e.kind() == clap::error::ErrorKind::MissingRequiredArgument)
            };
            if let Err(e) = crate::Cli::try_parse_from(&v)
                .map(|_| ())
                .or_else(|e| if help(&e) { Ok(()) } else { Err(e) })
            {
                let text = e.to_string();
                let first = text.lines().take(2).map(str::trim).collect::<Vec<_>>().join(" ");
                failures.push(format!("{file}:{line}: `{}`: {first}", v.join(" ")));
            }
        }
    }
    (parsed, failures)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_command_line_of_the_docs_parses() {
        let root = env!("CARGO_MANIFEST_DIR");
        let mut failures = Vec::new();
        let mut total = 0;
        for file in ["README.md", "docs/cli.md"] {
            let text = std::fs::read_to_string(format!("{root}/{file}")).expect(file);
            let (n, f) = check(file, &text);
            total += n;
            failures.extend(f);
        }
        // README's table alone has ~25 synopses with several alternatives each.
        assert!(total > 60, "only {total} command lines found: is the extraction broken?");
        assert!(failures.is_empty(), "{} do not parse:\n{}", failures.len(), failures.join("\n"));
    }

    #[test]
    fn synopses_expand_alternatives_options_and_placeholders() {
        let v =
            variants("btf synth material --kind lambert|knit --size N [--preview DIR] -o M.btf");
        let lines: Vec<String> = v.iter().map(|w| w.join(" ")).collect();
        assert_eq!(
            lines,
            [
                "btf synth material --kind lambert --size 2 -o M.btf",
                "btf synth material --kind lambert --size 2 --preview 2 -o M.btf",
                "btf synth material --kind knit --size 2 -o M.btf",
                "btf synth material --kind knit --size 2 --preview 2 -o M.btf",
            ]
        );
        let v = variants("btf knit ref [--chart C | --bcc F.bcc] [--light dir:θ,φ[,E]]… -o o.exr");
        let lines: Vec<String> = v.iter().map(|w| w.join(" ")).collect();
        assert!(
            lines.contains(&"btf knit ref --chart 2 --light dir:30,45,2 -o o.exr".into()),
            "{lines:?}"
        );
        assert!(lines.contains(&"btf knit ref --bcc F.bcc --light dir:30,45,2 -o o.exr".into()));
        assert!(lines.contains(&"btf knit ref -o o.exr".into()));
        let s = synopses("| `btf a --x p\\|q` / `btf b` |\n```sh\nbtf c \\\n  --d\n```\n");
        assert_eq!(s, [(1, "btf a --x p|q".into()), (1, "btf b".into()), (3, "btf c --d".into())]);
    }

    #[test]
    fn a_wrong_value_in_the_docs_would_be_caught() {
        let (_, f) = check("x.md", "`btf synth material --kind velvet -o m.btf`");
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(f[0].contains("velvet"), "{f:?}");
        let (_, f) = check("x.md", "`btf export IN.eig --format exr -o s.exr`");
        assert!(f.len() == 1 && f[0].contains("--slot"), "{f:?}");
    }
}
