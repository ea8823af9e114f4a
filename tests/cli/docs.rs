//! `ARCHITECTURE.md`'s equation index against the code. Every row names one numbered
//! equation of a paper (`[S03 eq. 6]`); every file its file column names exists under the
//! workspace root and cites that equation by its tag, either exactly or inside a list or
//! range of the same paper (`[S03 eq. 2–5]`, `[S03 eq. 3, 5]`, `[C03 eq. 5 and 9]`); a row
//! without a file says `not implemented: …` or `planned (issue #N)`; and every numbered
//! equation of the papers has exactly one row. The module map has one table per source
//! folder of the workspace (`### CRATE/src`, `### src` for the binary) and in it exactly one
//! row per Rust file, unit-test modules named `tests.rs` aside.

use std::collections::BTreeMap;
use std::path::Path;

/// The papers of the index and how many numbered equations each has (counted in
/// `/work/shared/papers/`): Sattler et al. 2003 (1)–(13), the thin-cloth paper (1)–(9),
/// Chen et al. 2003 (1)–(11), Wu & Yuksel 2019 (1)–(10), Huang et al. 2025 (1)–(17).
const PAPERS: &[(&str, u32)] = &[("S03", 13), ("TC", 9), ("C03", 11), ("W19", 10), ("H25", 17)];

/// How a file column without a file must begin.
const NO_FILE: &[&str] = &["not implemented: ", "planned (issue #"];

/// One row of the index.
struct Row {
    /// 1-based line in `ARCHITECTURE.md`.
    line: usize,
    /// The first cell, e.g. `[S03 eq. 6]`.
    tag: String,
    /// The third cell: backticked paths, or a reason.
    files: String,
}

impl Row {
    fn name(&self) -> String {
        format!("ARCHITECTURE.md:{} {}", self.line, self.tag)
    }
}

fn architecture() -> (std::path::PathBuf, String) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf();
    let text =
        std::fs::read_to_string(root.join("ARCHITECTURE.md")).expect("ARCHITECTURE.md reads");
    (root, text)
}

/// The table rows (`| [` …) between `## Equation index` and the next `## ` heading.
fn index_rows(text: &str) -> Vec<Row> {
    let mut rows = Vec::new();
    let mut inside = false;
    for (i, line) in text.lines().enumerate() {
        if line.starts_with("## ") {
            inside = line.trim() == "## Equation index";
            continue;
        }
        if !inside || !line.starts_with("| [") {
            continue;
        }
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        // A row `| a | b | c | d |` splits into ["", a, b, c, d, ""].
        assert!(
            cells.len() >= 5,
            "ARCHITECTURE.md:{}: an index row needs the columns equation | what | file(s) | where: {line}",
            i + 1
        );
        rows.push(Row { line: i + 1, tag: cells[1].to_string(), files: cells[3].to_string() });
    }
    rows
}

/// `[S03 eq. 6]` → `("S03", 6)`.
fn parse_tag(tag: &str) -> Option<(String, u32)> {
    let inner = tag.strip_prefix('[')?.strip_suffix(']')?;
    let (paper, number) = inner.split_once(" eq. ")?;
    Some((paper.to_string(), number.parse().ok()?))
}

/// Whether a citation list such as `2–5`, `3, 5` or `5 and 9` covers equation `n`.
fn list_covers(list: &str, n: u32) -> bool {
    list.replace(" and ", ",").split(',').map(str::trim).any(|item| {
        match item.split_once(['–', '-']) {
            Some((a, b)) => match (a.trim().parse::<u32>(), b.trim().parse::<u32>()) {
                (Ok(a), Ok(b)) => a <= n && n <= b,
                _ => false,
            },
            None => item.parse::<u32>() == Ok(n),
        }
    })
}

/// Whether `text` cites equation `n` of `paper` by its tag (`[PAPER eq. LIST]`).
fn cites(text: &str, paper: &str, n: u32) -> bool {
    let open = format!("[{paper} eq. ");
    text.match_indices(&open).any(|(at, _)| {
        let rest = &text[at + open.len()..];
        rest.find(']').is_some_and(|end| list_covers(&rest[..end], n))
    })
}

/// The backticked paths of a file column: tokens of path characters with a `/` (so a
/// formula such as `I = Φ/4π` is not taken for a path).
fn paths(files: &str) -> Vec<&str> {
    let path_char = |c: char| c.is_ascii_alphanumeric() || "_-./".contains(c);
    files
        .split('`')
        .skip(1)
        .step_by(2)
        .filter(|t| t.contains('/') && t.chars().all(path_char))
        .collect()
}

#[test]
fn citation_lists_are_read_as_documented() {
    assert!(list_covers("6", 6));
    assert!(list_covers("2–5", 3) && list_covers("2-5", 5) && !list_covers("2–5", 6));
    assert!(list_covers("3, 5", 5) && !list_covers("3, 5", 4));
    assert!(list_covers("5 and 9", 9) && !list_covers("5 and 9", 7));
    assert!(cites("see `[S03 eq. 10–12]` here", "S03", 11));
    assert!(!cites("[S03 eq. 10–12]", "TC", 11));
    assert!(!cites("Sattler et al. 2003, eq. 13", "S03", 13));
    assert!(!cites("[S03 eq. 13", "S03", 13));
    assert_eq!(paths("`btf-core/src/pca.rs`, `I = Φ/4π`, `Hemicube`"), ["btf-core/src/pca.rs"]);
}

#[test]
fn equation_index_files_exist_and_cite_their_equation() {
    let (root, text) = architecture();
    let rows = index_rows(&text);
    assert!(!rows.is_empty(), "ARCHITECTURE.md has no `## Equation index` table rows");
    let mut failures = Vec::new();
    for row in &rows {
        let Some((paper, n)) = parse_tag(&row.tag) else {
            failures.push(format!(
                "{}: the equation cell is not of the form `[PAPER eq. N]`",
                row.name()
            ));
            continue;
        };
        let files = paths(&row.files);
        if files.is_empty() {
            if !NO_FILE.iter().any(|p| row.files.starts_with(p)) {
                failures.push(format!(
                    "{}: names no file and does not begin with `not implemented: ` or `planned (issue #`: {:?}",
                    row.name(),
                    row.files
                ));
            }
            continue;
        }
        for file in files {
            if file.starts_with('/') || file.split('/').any(|c| c == "..") {
                failures
                    .push(format!("{}: `{file}` is not a path inside the workspace", row.name()));
                continue;
            }
            let path = root.join(file);
            match std::fs::read_to_string(&path) {
                Err(e) => failures.push(format!(
                    "{}: `{file}` does not exist or cannot be read ({e})",
                    row.name()
                )),
                Ok(code) => {
                    if !cites(&code, &paper, n) {
                        failures.push(format!(
                            "{}: `{file}` does not cite `[{paper} eq. {n}]` (exactly or in a list or range of {paper})",
                            row.name()
                        ));
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "equation index:\n{}", failures.join("\n"));
}

#[test]
fn equation_index_has_every_numbered_equation_once() {
    let (_, text) = architecture();
    let mut seen: BTreeMap<(String, u32), Vec<usize>> = BTreeMap::new();
    for row in index_rows(&text) {
        if let Some(key) = parse_tag(&row.tag) {
            seen.entry(key).or_default().push(row.line);
        }
    }
    let mut failures = Vec::new();
    for &(paper, count) in PAPERS {
        for n in 1..=count {
            match seen.get(&(paper.to_string(), n)).map(Vec::as_slice) {
                None | Some([]) => failures.push(format!("[{paper} eq. {n}] has no row")),
                Some([_]) => {}
                Some(lines) => {
                    failures.push(format!("[{paper} eq. {n}] has several rows, at lines {lines:?}"))
                }
            }
        }
    }
    for ((paper, n), lines) in &seen {
        match PAPERS.iter().find(|(p, _)| p == paper) {
            None => failures.push(format!("ARCHITECTURE.md:{lines:?}: [{paper} eq. {n}] is not a paper of the index")),
            Some(&(_, count)) if *n > count => failures.push(format!(
                "ARCHITECTURE.md:{lines:?}: [{paper} eq. {n}] does not exist ({paper} numbers 1–{count})"
            )),
            Some(_) => {}
        }
    }
    assert!(failures.is_empty(), "equation index:\n{}", failures.join("\n"));
}

/// The lines of the first fenced `sh` block after the heading `heading` of README.md.
fn readme_block(heading: &str) -> Vec<String> {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md"))
        .expect("README.md reads");
    let after = text.split_once(heading).unwrap_or_else(|| panic!("README has no {heading}")).1;
    let block = after.split_once("```sh\n").expect("an sh block").1;
    block.split_once("```").expect("closed").0.lines().map(str::to_string).collect()
}

/// README's "A first session" runs as written, in a shell, in an empty folder (the parse
/// test of every README command line is `src/readme_commands.rs`); each command says what it
/// wrote where, and the round trip through a Bonn folder gives the same store back.
#[test]
fn the_readme_first_session_runs_as_written() {
    let lines = readme_block("## A first session");
    assert!(lines.len() >= 8 && lines.iter().all(|l| l.starts_with("btf ")), "{lines:?}");
    let d = crate::common::Dir::new();
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_btf")).parent().unwrap().to_path_buf();
    let path = format!("{}:{}", bin_dir.display(), std::env::var("PATH").unwrap_or_default());
    for line in &lines {
        let o = std::process::Command::new("sh")
            .args(["-c", line])
            .current_dir(d.tmp.path())
            .env("PATH", &path)
            .env("BTF_NO_PROGRESS", "1")
            .output()
            .expect("sh runs");
        let (out, err) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
        assert!(o.status.success(), "README: `{line}` failed:\n{out}\n{err}");
        // The last word is what the command wrote (or read, for inspect): it is named.
        let target = line.split_whitespace().last().unwrap();
        assert!(out.contains(target) || err.contains(target), "`{line}` says nothing of {target}");
    }
    // The Bonn folder round trip with `--image png16` keeps every value (16-bit PNG of
    // values ≤ 1: ≤ 2⁻¹⁶ relative; the 8-bit default would lose up to 2.4/255 of the peak).
    let a = btf_core::store::BtfStore::open(&d.path("corduroy.btf")).unwrap();
    let b = btf_core::store::BtfStore::open(&d.path("again.btf")).unwrap();
    assert_eq!((a.meta().n_views(), a.meta().n_lights()), (5, 5));
    let (x, y) = (a.read_image(3, 2).unwrap(), b.read_image(3, 2).unwrap());
    let peak = x.iter().fold(0f32, |m, &v| m.max(v)).max(1.0);
    let worst = x.iter().zip(&y).map(|(p, q)| (p - q).abs()).fold(0f32, f32::max);
    assert!(worst <= peak / 65535.0, "round trip error {worst} (peak {peak})");
}

/// The module map's tables: heading's source folder (`btf-core/src`, `src`) → the backticked
/// `.rs` paths of each row's first cell, with the 1-based line of each.
fn module_map(text: &str) -> BTreeMap<String, Vec<(String, usize)>> {
    let mut tables: BTreeMap<String, Vec<(String, usize)>> = BTreeMap::new();
    let mut inside = false;
    let mut current: Option<String> = None;
    for (i, line) in text.lines().enumerate() {
        if line.starts_with("## ") {
            inside = line.trim() == "## Module map";
            current = None;
            continue;
        }
        if !inside {
            continue;
        }
        if let Some(h) = line.strip_prefix("### ") {
            let folder = h.split_whitespace().next().unwrap_or("");
            assert!(
                folder == "src" || folder.ends_with("/src"),
                "ARCHITECTURE.md:{}: a module map heading names no source folder: {line}",
                i + 1
            );
            current = Some(folder.to_string());
            tables.entry(folder.to_string()).or_default();
            continue;
        }
        let Some(folder) = &current else { continue };
        if let Some(first) = line.strip_prefix('|').and_then(|l| l.split('|').next()) {
            for token in first.split('`').skip(1).step_by(2).filter(|t| t.ends_with(".rs")) {
                tables.get_mut(folder).unwrap().push((token.to_string(), i + 1));
            }
        }
    }
    tables
}

/// The `.rs` files under `dir`, as paths relative to it with `/` separators.
fn rust_files(dir: &Path, prefix: &str, out: &mut Vec<String>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if path.is_dir() {
            rust_files(&path, &format!("{prefix}{name}/"), out);
        } else if name.ends_with(".rs") {
            out.push(format!("{prefix}{name}"));
        }
    }
}

#[test]
fn module_map_has_one_row_per_source_file() {
    let (root, text) = architecture();
    let tables = module_map(&text);
    let cargo = std::fs::read_to_string(root.join("Cargo.toml")).expect("Cargo.toml reads");
    let members = cargo
        .lines()
        .find_map(|l| l.trim().strip_prefix("members = ["))
        .expect("the workspace's members line");
    let mut folders: Vec<String> = members
        .trim_end_matches(']')
        .split(',')
        .map(|m| format!("{}/src", m.trim().trim_matches('"')))
        .collect();
    folders.push("src".into());
    let mut failures = Vec::new();
    for folder in &folders {
        let Some(rows) = tables.get(folder) else {
            failures.push(format!("no `### {folder}` table in the module map"));
            continue;
        };
        let mut files = Vec::new();
        rust_files(&root.join(folder), "", &mut files);
        for f in files.iter().filter(|f| !f.ends_with("/tests.rs") && *f != "tests.rs") {
            let lines: Vec<usize> = rows.iter().filter(|(t, _)| t == f).map(|r| r.1).collect();
            match lines.len() {
                0 => failures.push(format!("{folder}/{f} has no row under `### {folder}`")),
                1 => {}
                _ => failures.push(format!("{folder}/{f} has rows at lines {lines:?}")),
            }
        }
        for (t, line) in rows {
            if !files.contains(t) {
                failures.push(format!("ARCHITECTURE.md:{line}: `{t}` is no file of {folder}"));
            }
        }
    }
    for folder in tables.keys().filter(|f| !folders.contains(f)) {
        failures.push(format!("`### {folder}` is no source folder of the workspace"));
    }
    assert!(failures.is_empty(), "module map out of date:\n{}", failures.join("\n"));
}
