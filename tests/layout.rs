//! The core's house: no module imports one that imports it back (read from the sources: each
//! file's `crate::…` and `super::…` paths in code, groups expanded and the root's re-exports
//! followed to their modules, its tests and comments left out), so data flows one way.

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

/// The word at the start of `text` (a module's or an item's name), and what follows it.
fn word(text: &str) -> (&str, &str) {
    let end = text
        .find(|c: char| !(c.is_alphanumeric() || c == '_'))
        .unwrap_or(text.len());
    text.split_at(end)
}

/// The paths of a `use` tree at the start of `text`, after `prefix`: `a::b`, and each branch
/// of a group `a::{b, c::{d, e}}`.
fn tree(text: &str, prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
    let mut path = prefix;
    let mut rest = text;
    loop {
        let (name, after) = word(rest);
        if name.is_empty() {
            break;
        }
        path.push(name.to_string());
        match after.strip_prefix("::") {
            Some(more) => rest = more,
            None => {
                rest = "";
                break;
            }
        }
    }
    if let Some(group) = rest.strip_prefix('{') {
        // Each branch at depth 0 of the group, up to its closing brace.
        let (mut depth, mut start) = (0, 0);
        for (at, c) in group.char_indices() {
            match c {
                '{' => depth += 1,
                // (A trailing comma leaves an empty branch: none.)
                '}' if depth == 0 => {
                    let branch = group[start..at].trim();
                    if !branch.is_empty() {
                        tree(branch, path.clone(), out);
                    }
                    return;
                }
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    tree(group[start..at].trim_start(), path.clone(), out);
                    start = at + 1;
                }
                _ => {}
            }
        }
    } else if !path.is_empty() {
        out.push(path);
    }
}

/// Every path after `start` (`crate::`, `super::`) in `text`, groups expanded.
fn paths(text: &str, start: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for (at, _) in text.match_indices(start) {
        let before = text[..at].chars().last();
        if !before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            tree(&text[at + start.len()..], Vec::new(), &mut out);
        }
    }
    out
}

/// The crate root's re-exports (`pub use model::device::{Device, …}`): each name and the path
/// it stands for, so that `crate::Device` counts as an import of `model::device`.
fn root_names(lib: &str) -> BTreeMap<String, Vec<String>> {
    let mut names = BTreeMap::new();
    // Code only, each `pub use … ;` read whole (a group spans lines).
    let code: String = lib
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join(" ");
    for (at, _) in code.match_indices("pub use ") {
        let used = &code[at + "pub use ".len()..];
        let used = &used[..used.find(';').unwrap_or(used.len())];
        let mut found = Vec::new();
        tree(used, Vec::new(), &mut found);
        for path in found {
            if let Some(name) = path.last() {
                names.insert(name.clone(), path.clone());
            }
        }
    }
    names
}

/// Each module of the crate whose sources are under `root` (its root file `lib.rs`), and the
/// modules it imports.
fn imports(root: &Path) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let mut files = BTreeMap::new();
    modules(root, &[], &mut files);
    let known: BTreeSet<Vec<String>> = files.keys().cloned().collect();
    let lib = std::fs::read_to_string(root.join("lib.rs")).unwrap_or_default();
    let names = root_names(&lib);
    // The longest module a path names (a root re-export: the module it comes from).
    let resolve = |words: &[String]| {
        let words = match words.first().and_then(|w| names.get(w)) {
            Some(full) => full.clone(),
            None => words.to_vec(),
        };
        (1..=words.len())
            .rev()
            .map(|n| words[..n].to_vec())
            .find(|m| !m.is_empty() && known.contains(m))
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
        let found =
            paths(text, "crate::")
                .into_iter()
                .chain(paths(text, "super::").into_iter().map(|words| {
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
    uses
}

/// Every import circle among `uses`: a module reached again from itself, said with its path.
fn circles(uses: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Vec<String> {
    let mut found = Vec::new();
    for start in uses.keys() {
        let mut seen = BTreeSet::new();
        let mut stack: Vec<(Vec<String>, Vec<String>)> = vec![(start.clone(), vec![])];
        'walk: while let Some((at, trail)) = stack.pop() {
            for next in uses.get(&at).into_iter().flatten() {
                let mut path = trail.clone();
                path.push(next.join("::"));
                if next == start {
                    found.push(format!(
                        "{} imports {}, which imports it back",
                        start.join("::"),
                        path.join(" → ")
                    ));
                    break 'walk;
                }
                if seen.insert(next.clone()) {
                    stack.push((next.clone(), path));
                }
            }
        }
    }
    found
}

#[test]
fn no_module_of_the_core_imports_one_that_imports_it_back() {
    let uses = imports(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    let found = circles(&uses);
    assert!(found.is_empty(), "{found:#?}");
    assert!(uses.len() > 40, "{} modules read", uses.len());
    // The reader sees imports at all: the board runs the controller, through a group and a
    // root re-export alike.
    let board = uses
        .get(&vec!["board".to_string()])
        .expect("src/board/mod.rs read");
    assert!(
        board.contains(&vec!["controller".to_string()]),
        "the board's imports read as {board:?}"
    );
}

/// host-sim's modules likewise (its library and its binary's, read as one tree).
#[test]
fn no_module_of_host_sim_imports_one_that_imports_it_back() {
    let uses = imports(&Path::new(env!("CARGO_MANIFEST_DIR")).join("host-sim/src"));
    assert!(uses.len() > 30, "{} modules read", uses.len());
    let found = circles(&uses);
    assert!(found.is_empty(), "{found:#?}");
}

/// The firmware's library likewise (its `bin/` are wiring, each a crate of its own).
#[test]
fn no_module_of_the_firmware_imports_one_that_imports_it_back() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("firmware/src");
    let uses: BTreeMap<_, _> = imports(&root)
        .into_iter()
        .filter(|(module, _)| module.first().is_none_or(|m| m != "bin"))
        .collect();
    assert!(uses.len() > 8, "{} modules read", uses.len());
    let found = circles(&uses);
    assert!(found.is_empty(), "{found:#?}");
}

/// Every `.rs` file under `dir` (vendored code left out), with its path from `top`.
fn sources(top: &Path, dir: &Path, out: &mut Vec<(String, usize)>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            if path.file_name().is_some_and(|n| n != "vendor") {
                sources(top, &path, out);
            }
        } else if path.extension().is_some_and(|e| e == "rs") {
            let lines = std::fs::read_to_string(&path).unwrap().lines().count();
            let name = path
                .strip_prefix(top)
                .unwrap()
                .to_string_lossy()
                .to_string();
            out.push((name, lines));
        }
    }
}

/// Paths a crate's own modules take through its root's re-exports (`crate::Device` for
/// `crate::model::device::Device`): the re-exports are for users, a module names where a
/// thing lives.
fn through_root(root: &Path) -> Vec<String> {
    let lib = std::fs::read_to_string(root.join("lib.rs")).unwrap_or_default();
    let names = root_names(&lib);
    let mut files = BTreeMap::new();
    modules(root, &[], &mut files);
    let mut found = Vec::new();
    for (module, file) in &files {
        if module.is_empty() {
            continue;
        }
        let text = std::fs::read_to_string(file).unwrap();
        for words in paths(&text, "crate::") {
            if words.first().is_some_and(|w| names.contains_key(w)) {
                found.push(format!("{}: crate::{}", file.display(), words.join("::")));
            }
        }
    }
    found
}

#[test]
fn no_module_imports_through_its_crate_roots_re_exports() {
    let top = Path::new(env!("CARGO_MANIFEST_DIR"));
    for crate_root in ["src", "firmware/src"] {
        let found = through_root(&top.join(crate_root));
        assert!(found.is_empty(), "{found:#?}");
    }
}

/// No source file of the core, the firmware, host-sim or the Python package over 1,000 lines:
/// a room a newcomer reads whole.
#[test]
fn no_source_file_is_over_a_thousand_lines() {
    let top = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for dir in ["src", "firmware/src", "host-sim/src", "python/src"] {
        sources(top, &top.join(dir), &mut files);
    }
    assert!(files.len() > 120, "{} files read", files.len());
    let over: Vec<String> = files
        .iter()
        .filter(|(_, lines)| *lines > 1_000)
        .map(|(name, lines)| format!("{name}: {lines} lines"))
        .collect();
    assert!(over.is_empty(), "over 1,000 lines: {over:?}");
}
