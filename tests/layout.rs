//! The core's house: no module imports one that imports it back (read from the sources: each
//! file's `crate::…` and `super::…` paths in code, its tests and comments left out), so data
//! flows one way.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every module of `src/` by its path (`controller::settings`), with its file.
fn modules(dir: &Path, prefix: &[String], out: &mut BTreeMap<Vec<String>, PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        if path.is_dir() {
            let mut inner = prefix.to_vec();
            inner.push(name);
            modules(&path, &inner, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let mut module = prefix.to_vec();
            if name != "mod" && name != "lib" {
                module.push(name);
            }
            out.insert(module, path);
        }
    }
}

/// The words of each `a::b::c` path after `start` in `text`.
fn paths<'a>(text: &'a str, start: &'a str) -> impl Iterator<Item = Vec<String>> + 'a {
    text.match_indices(start).filter_map(move |(at, _)| {
        let before = text[..at].chars().last();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            return None;
        }
        let rest = &text[at + start.len()..];
        let words: Vec<String> = rest
            .split("::")
            .map(|w| {
                w.chars()
                    .take_while(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '_')
                    .collect::<String>()
            })
            .scan(true, |go, w| {
                let whole = *go && !w.is_empty();
                *go = whole;
                whole.then_some(w)
            })
            .collect();
        (!words.is_empty()).then_some(words)
    })
}

#[test]
fn no_module_of_the_core_imports_one_that_imports_it_back() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = BTreeMap::new();
    modules(&root, &[], &mut files);
    let known: BTreeSet<Vec<String>> = files.keys().cloned().collect();
    // The longest module a path names.
    let resolve = |words: &[String]| {
        (1..=words.len())
            .rev()
            .map(|n| words[..n].to_vec())
            .find(|m| known.contains(m))
    };
    let mut uses: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (module, file) in &files {
        let text = std::fs::read_to_string(file).unwrap();
        // Its tests left out: from the `#[cfg(test)]` before `mod tests`.
        let text = match text.find("\nmod tests {") {
            Some(at) => &text[..text[..at].rfind("#[cfg(test)]").unwrap_or(at)],
            None => text.as_str(),
        };
        // Code only: a doc comment naming a module imports nothing.
        let text: String = text
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        let text = text.as_str();
        let parent = &module[..module.len().saturating_sub(1)];
        let found = paths(text, "crate::").chain(paths(text, "super::").map(|words| {
            let mut full = parent.to_vec();
            full.extend(words);
            full
        }));
        let edges = uses.entry(module.clone()).or_default();
        for target in found.filter_map(|w| resolve(&w)) {
            // A module's own parent or itself is not an import back.
            if target != *module && !module.starts_with(&target) {
                edges.insert(target);
            }
        }
    }
    // A cycle: a module reached again from itself.
    for start in uses.keys() {
        let mut seen = BTreeSet::new();
        let mut stack: Vec<(Vec<String>, Vec<String>)> = vec![(start.clone(), vec![])];
        while let Some((at, trail)) = stack.pop() {
            for next in uses.get(&at).into_iter().flatten() {
                let mut path = trail.clone();
                path.push(next.join("::"));
                assert!(
                    next != start,
                    "{} imports {}, which imports it back",
                    start.join("::"),
                    path.join(" → ")
                );
                if seen.insert(next.clone()) {
                    stack.push((next.clone(), path));
                }
            }
        }
    }
    assert!(uses.len() > 40, "{} modules read", uses.len());
}
