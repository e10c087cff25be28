//! Every relative link and image in README.md and docs/**/*.md resolves: the file or
//! folder exists, and a `#anchor` (in the same file or in another Markdown file) names a
//! heading there, slugged as GitHub does. External links (http, https, mailto, ...) are
//! not checked. The checker itself is tested on broken links below.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A link found in a Markdown file: its target as written and the line it is on.
#[derive(Debug, Clone, PartialEq)]
struct Link {
    target: String,
    line: usize,
}

/// Lines of `text` outside fenced code blocks, with their 1-based numbers.
fn prose_lines(text: &str) -> Vec<(usize, &str)> {
    let mut fence: Option<&str> = None;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let t = line.trim_start();
        let marker = if t.starts_with("```") {
            Some("```")
        } else if t.starts_with("~~~") {
            Some("~~~")
        } else {
            None
        };
        match (fence, marker) {
            (None, Some(m)) => fence = Some(m),
            (Some(f), Some(m)) if f == m => fence = None,
            (None, None) => out.push((i + 1, line)),
            _ => {}
        }
    }
    out
}

/// `line` without its inline code spans (a link inside backticks is not a link).
fn without_code_spans(line: &str) -> String {
    let mut out = String::new();
    let mut rest = line;
    while let Some(start) = rest.find('`') {
        out.push_str(&rest[..start]);
        let ticks = rest[start..].chars().take_while(|&c| c == '`').count();
        let after = &rest[start + ticks..];
        let close = "`".repeat(ticks);
        match after.find(&close) {
            Some(end) => rest = &after[end + ticks..],
            None => {
                rest = after;
                break;
            }
        }
    }
    out.push_str(rest);
    out
}

/// The links and images of a Markdown text: inline `[text](target)` and `![alt](target)`,
/// reference definitions `[label]: target`, and HTML `src="..."` / `href="..."`.
fn links(text: &str) -> Vec<Link> {
    let mut found = Vec::new();
    for (n, raw) in prose_lines(text) {
        let line = without_code_spans(raw);
        let mut push = |t: &str| {
            let t = t.trim();
            let t = t
                .strip_prefix('<')
                .and_then(|t| t.strip_suffix('>'))
                .unwrap_or(t);
            // Drop an optional title: [x](file.md "title").
            let t = t.split_whitespace().next().unwrap_or("");
            if !t.is_empty() {
                found.push(Link {
                    target: t.to_string(),
                    line: n,
                });
            }
        };
        let bytes = line.as_bytes();
        let mut i = 0;
        while let Some(off) = line[i..].find("](") {
            let start = i + off + 2;
            // The target ends at the matching ')', allowing balanced parentheses inside.
            let mut depth = 1;
            let mut end = start;
            while end < bytes.len() {
                match bytes[end] {
                    b'(' => depth += 1,
                    b')' => {
                        depth -= 1;
                        if depth == 0 {
                            break;
                        }
                    }
                    _ => {}
                }
                end += 1;
            }
            push(&line[start..end.min(bytes.len())]);
            i = end.min(bytes.len());
        }
        let t = line.trim_start();
        if t.starts_with('[') {
            if let Some(close) = t.find("]:") {
                push(&t[close + 2..]);
            }
        }
        for attr in ["src=\"", "href=\""] {
            let mut rest = line.as_str();
            while let Some(p) = rest.find(attr) {
                let v = &rest[p + attr.len()..];
                let end = v.find('"').unwrap_or(v.len());
                push(&v[..end]);
                rest = &v[end..];
            }
        }
    }
    found
}

/// GitHub's anchor of a heading's text: inline code and link syntax reduced to their
/// text, lower case, everything but letters, digits, '_', '-' and spaces dropped, spaces
/// turned into '-'.
fn slug(heading: &str) -> String {
    // [text](url) -> text
    let mut text = String::new();
    let mut rest = heading;
    while let Some(open) = rest.find('[') {
        match rest[open..].find("](") {
            Some(mid) => {
                let after = &rest[open + mid + 2..];
                match after.find(')') {
                    Some(close) => {
                        text.push_str(&rest[..open]);
                        text.push_str(&rest[open + 1..open + mid]);
                        rest = &after[close + 1..];
                    }
                    None => break,
                }
            }
            None => break,
        }
    }
    text.push_str(rest);
    text.to_lowercase()
        .chars()
        .filter(|&c| c.is_alphanumeric() || c == '_' || c == '-' || c == ' ')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors a Markdown text defines: its ATX headings' slugs (repeats numbered `-1`,
/// `-2`, ... as on GitHub) and explicit `id="..."` / `name="..."` attributes.
fn anchors(text: &str) -> Vec<String> {
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut out = Vec::new();
    for (_, line) in prose_lines(text) {
        let t = line.trim_start();
        let hashes = t.chars().take_while(|&c| c == '#').count();
        if (1..=6).contains(&hashes) && t[hashes..].starts_with(' ') {
            let title = t[hashes..].trim().trim_end_matches('#').trim();
            let base = slug(title);
            let n = seen.entry(base.clone()).or_insert(0);
            out.push(if *n == 0 {
                base.clone()
            } else {
                format!("{base}-{n}")
            });
            *n += 1;
        }
        for attr in ["id=\"", "name=\""] {
            let mut rest = t;
            while let Some(p) = rest.find(attr) {
                let v = &rest[p + attr.len()..];
                let end = v.find('"').unwrap_or(v.len());
                out.push(v[..end].to_string());
                rest = &v[end..];
            }
        }
    }
    out
}

/// Whether a target is external (has a URL scheme such as `https:` or `mailto:`).
fn is_external(target: &str) -> bool {
    let scheme: String = target.chars().take_while(|&c| c != ':').collect();
    scheme.len() < target.len()
        && !scheme.is_empty()
        && scheme
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
        && !scheme.contains('/')
}

/// Decodes `%XX` escapes (a link to `my%20file.md`).
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let Ok(v) = u8::from_str_radix(&s[i + 1..i + 3], 16) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The broken links of the Markdown file `file` (whose text is `text`), each described
/// as `file:line: target: problem`. `read` gives the text of another Markdown file.
fn broken_links(file: &Path, text: &str, read: &dyn Fn(&Path) -> Option<String>) -> Vec<String> {
    let dir = file.parent().unwrap_or(Path::new(""));
    let mut bad = Vec::new();
    for l in links(text) {
        if is_external(&l.target) {
            continue;
        }
        let (path, anchor) = match l.target.split_once('#') {
            Some((p, a)) => (p, Some(a)),
            None => (l.target.as_str(), None),
        };
        let path = percent_decode(path.split('?').next().unwrap_or(""));
        let fail = |why: String| format!("{}:{}: {}: {why}", file.display(), l.line, l.target);
        let (target_file, target_text) = if path.is_empty() {
            (file.to_path_buf(), Some(text.to_string()))
        } else {
            let p = if let Some(abs) = path.strip_prefix('/') {
                // Relative to the repository root, as GitHub resolves it.
                PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(abs)
            } else {
                dir.join(&path)
            };
            if !p.exists() {
                bad.push(fail(format!("{} does not exist", p.display())));
                continue;
            }
            let md = p.extension().is_some_and(|e| e == "md");
            (p.clone(), if md { read(&p) } else { None })
        };
        if let Some(a) = anchor.filter(|a| !a.is_empty()) {
            match target_text {
                Some(t) => {
                    let a = percent_decode(a).to_lowercase();
                    if !anchors(&t).contains(&a) {
                        bad.push(fail(format!(
                            "no heading with the anchor #{a} in {}",
                            target_file.display()
                        )));
                    }
                }
                None if target_file.is_dir() => {
                    bad.push(fail("an anchor into a folder".into()));
                }
                // Anchors into other files (line numbers in code) are not checked.
                None => {}
            }
        }
    }
    bad
}

/// README.md and every Markdown file under docs/.
fn doc_files(root: &Path) -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        let mut entries: Vec<_> = entries.filter_map(|e| e.ok()).map(|e| e.path()).collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|e| e == "md") {
                out.push(p);
            }
        }
    }
    let mut files = vec![root.join("README.md")];
    walk(&root.join("docs"), &mut files);
    files
}

#[test]
fn every_relative_link_in_the_readme_and_docs_resolves() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let files = doc_files(root);
    assert!(files.len() > 5, "docs/ holds too few files: {files:?}");
    let read = |p: &Path| std::fs::read_to_string(p).ok();
    let mut bad = Vec::new();
    let mut checked = 0;
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        checked += links(&text).len();
        bad.extend(broken_links(f, &text, &read));
    }
    assert!(checked > 30, "only {checked} links found");
    assert!(bad.is_empty(), "broken links:\n{}", bad.join("\n"));
}

#[test]
fn the_readme_starts_with_the_two_commands_and_links_every_doc() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let first_block = readme.split("```").nth(1).unwrap_or("");
    assert!(
        first_block.contains("cargo run --release -- train --config configs/quick.toml")
            && first_block.contains("cargo test "),
        "{first_block}"
    );
    let index = std::fs::read_to_string(root.join("docs/README.md")).unwrap();
    let targets: Vec<String> = links(&index).into_iter().map(|l| l.target).collect();
    for f in std::fs::read_dir(root.join("docs")).unwrap() {
        let name = f.unwrap().file_name().to_string_lossy().into_owned();
        if name.ends_with(".md") && name != "README.md" {
            assert!(
                targets.contains(&name),
                "docs/README.md does not link {name}"
            );
        }
    }
}

#[cfg(test)]
mod checker {
    use super::*;

    fn check(file: &str, text: &str, others: &[(&str, &str)]) -> Vec<String> {
        let others: Vec<(PathBuf, String)> = others
            .iter()
            .map(|(p, t)| (PathBuf::from(p), t.to_string()))
            .collect();
        let read = move |p: &Path| others.iter().find(|(q, _)| q == p).map(|(_, t)| t.clone());
        broken_links(Path::new(file), text, &read)
    }

    #[test]
    fn slugs_follow_github() {
        assert_eq!(slug("Python (`grasp_rl`)"), "python-grasp_rl");
        assert_eq!(slug("Results (Table I)"), "results-table-i");
        assert_eq!(
            slug("On the robot: `grasp calibrate` and `grasp run`"),
            "on-the-robot-grasp-calibrate-and-grasp-run"
        );
        assert_eq!(
            slug("The procedural stream (`procedural`)"),
            "the-procedural-stream-procedural"
        );
        assert_eq!(slug("See [the docs](docs/x.md) now"), "see-the-docs-now");
        assert_eq!(slug("Ein Über-Test, 2 Mal"), "ein-über-test-2-mal");
        let a = anchors("# A\n## A\n```\n# not a heading\n```\n<a id=\"x\"></a>\n#nope\n");
        assert_eq!(a, vec!["a", "a-1", "x"]);
    }

    #[test]
    fn links_are_found_outside_code_only() {
        let text = "see [a](a.md) and ![img](i/p.svg \"title\")\n`[not](x.md)`\n```\n[no](y.md)\n```\n[ref]: <r.md>\n<img src=\"s.png\"> [p](f(x).md)\n";
        let t: Vec<String> = links(text).into_iter().map(|l| l.target).collect();
        assert_eq!(t, vec!["a.md", "i/p.svg", "r.md", "f(x).md", "s.png"]);
        assert!(is_external("https://x.org/a") && is_external("mailto:a@b"));
        assert!(!is_external("docs/a.md") && !is_external("#x") && !is_external("a.md#b:c"));
        assert_eq!(percent_decode("my%20file.md"), "my file.md");
    }

    #[test]
    fn broken_links_and_anchors_are_reported() {
        let root = env!("CARGO_MANIFEST_DIR");
        let readme = format!("{root}/README.md");
        let doc = format!("{root}/docs/results.md");
        let text =
            "# Top\n[ok](#top) [bad](#nowhere)\n[file](docs/results.md) [missing](docs/nope.md)\n\
                    [anchor](docs/results.md#results-table-i) [wrong](docs/results.md#no-such)\n\
                    ![img](docs/no.svg) [web](https://example.com/missing) [dir](docs/)\n";
        let bad = check(
            &readme,
            text,
            &[(&doc, "# Results\n## Results (Table I)\n")],
        );
        assert_eq!(bad.len(), 4, "{bad:#?}");
        assert!(bad[0].contains("#nowhere: no heading with the anchor #nowhere"));
        assert!(bad[1].contains("docs/nope.md does not exist"));
        assert!(bad[2].contains("no heading with the anchor #no-such"));
        assert!(bad[3].contains("docs/no.svg does not exist"));
        assert!(bad[0].contains("README.md:2:"), "{}", bad[0]);
        assert!(check(
            &readme,
            "[a](docs/results.md#results-table-i)",
            &[(&doc, "## Results (Table I)")]
        )
        .is_empty());
    }
}
