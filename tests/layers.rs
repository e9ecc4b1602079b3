//! Layers point one way (issue 33): model -> engine -> calibrate/optim ->
//! fit/diagnose/campaigns -> cli and python. Two modules that import each other, directly or
//! through a loop, cannot be understood, tested or changed one at a time; a lower layer that
//! reaches up pulls the whole stack into every change below it.
//!
//! The check reads the source, not the compiled crate: every `crate::`/`super::` path in
//! `src/**/*.rs` (use trees and qualified paths alike) is resolved against the module it is
//! written in, and becomes an edge between the two modules it joins, at the level where they
//! part: between top-level modules (`fit` -> `calibrate`) and between sibling submodules
//! (`cli::multi` -> `cli::study`). A parent reaching into its own child, or a child using an
//! item of its parent, is how a module is built and is not counted.
//!
//! The parser is small on purpose (comments and literals stripped, then tokens); its tests
//! below pin what it must see, and the synthetic-graph tests show that the check can fail.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The declared order of the top-level modules, lowest first. A module may use modules of
/// its own rank or below, never above; cycles are refused separately, so two modules of one
/// rank may not use each other either.
const LAYERS: &[&[&str]] = &[
    // leaf helpers every layer may use: the lane type (`lane`) and the vector math over it
    // (`lane_math`), the SIMD path the cpu engine takes (`simd`), the integer codes the Rust
    // and WGSL kernels share, and `schema` (the input bounds; it imports nothing)
    &["lane", "lane_math", "simd", "kernel_codes", "schema"],
    &["model"],
    &["engine"],
    // files, tables and figures: serve every layer above the engine
    &["io", "plot"],
    // engines put to work: calibration, optimisation, the DEM cross-check (issue 33's
    // parallel `dem` branch), and the campaign protocol that campaigns of optimisations and
    // DEM checks both implement
    &["calibrate", "optim", "dem", "protocol"],
    // workflows over them: fitting, diagnosis, campaigns of many runs, and a scenario
    // resolved from a config (or a run's run.toml) and overrides
    &["fit", "diagnose", "campaigns", "scenario_request"],
    &["cli"],
];

/// One `crate::`/`super::` path: where it is written and the absolute module path it names.
#[derive(Clone, Debug, PartialEq)]
struct Reference {
    file: String,
    line: usize,
    /// the module the path is written in (file module plus inline `mod x { }` blocks)
    from: Vec<String>,
    /// the path resolved from the crate root (`crate::a::b` -> [a, b])
    to: Vec<String>,
}

#[derive(Clone, Debug, PartialEq)]
enum Token {
    Ident(String),
    /// `::`
    PathSep,
    Punct(char),
}

/// Source text without comments, string, char and byte literals, cut into tokens with the
/// line each starts on. Lifetimes (`'a`) survive as an apostrophe and an identifier.
fn tokenize(src: &str) -> Vec<(Token, usize)> {
    let s: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line) = (0, 1);
    let bump_lines = |from: usize, to: usize, line: &mut usize| {
        *line += s[from..to].iter().filter(|&&c| c == '\n').count();
    };
    while i < s.len() {
        let c = s[i];
        let next = s.get(i + 1).copied();
        if c == '\n' {
            line += 1;
            i += 1;
        } else if c.is_whitespace() {
            i += 1;
        } else if c == '/' && next == Some('/') {
            while i < s.len() && s[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            // block comments nest in Rust
            let (start, mut depth) = (i, 0);
            while i < s.len() {
                if s[i] == '/' && s.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if s[i] == '*' && s.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            bump_lines(start, i.min(s.len()), &mut line);
        } else if c == '"' {
            let start = i;
            i += 1;
            while i < s.len() && s[i] != '"' {
                i += if s[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            bump_lines(start, i.min(s.len()), &mut line);
        } else if (c == 'r' || (c == 'b' && next == Some('r'))) && {
            let j = if c == 'b' { i + 2 } else { i + 1 };
            let mut k = j;
            while s.get(k) == Some(&'#') {
                k += 1;
            }
            s.get(k) == Some(&'"') && (k > j || s.get(j) == Some(&'"'))
        } {
            // raw string: r"..", r#".."#, br".."
            let start = i;
            i += if c == 'b' { 2 } else { 1 };
            let mut hashes = 0;
            while s[i] == '#' {
                hashes += 1;
                i += 1;
            }
            i += 1;
            loop {
                if i >= s.len() {
                    break;
                }
                if s[i] == '"' && (0..hashes).all(|h| s.get(i + 1 + h) == Some(&'#')) {
                    i += 1 + hashes;
                    break;
                }
                i += 1;
            }
            bump_lines(start, i.min(s.len()), &mut line);
        } else if c == 'b' && next == Some('"') {
            i += 1; // the byte string's quote is taken by the string branch next round
        } else if c == '\'' {
            // char literal ('x', '\n', '\u{1F600}') or a lifetime ('a)
            if next == Some('\\') {
                i += 3; // the quote, the backslash and the escaped character ('\'' included)
                while i < s.len() && s[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if s.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                out.push((Token::Punct('\''), line));
                i += 1;
            }
        } else if c.is_alphanumeric() || c == '_' {
            let start = i;
            while i < s.len() && (s[i].is_alphanumeric() || s[i] == '_') {
                i += 1;
            }
            let mut word: String = s[start..i].iter().collect();
            if word == "r" && s.get(i) == Some(&'#') && s.get(i + 1).is_some_and(|c| c.is_alphabetic() || *c == '_') {
                // r#ident: a raw identifier names the same item as ident
                let start = i + 1;
                i = start;
                while i < s.len() && (s[i].is_alphanumeric() || s[i] == '_') {
                    i += 1;
                }
                word = s[start..i].iter().collect();
            }
            out.push((Token::Ident(word), line));
        } else if c == ':' && next == Some(':') {
            out.push((Token::PathSep, line));
            i += 2;
        } else {
            out.push((Token::Punct(c), line));
            i += 1;
        }
    }
    out
}

/// Every path a use tree starting at `tokens[*at]` spells out (`a::{b, c::{self, d}}` gives
/// a::b, a::c, a::c::d), each as its segments; `*` and `as x` end a path. Qualified paths in
/// expressions are the same grammar without braces, ending at the first non-segment token.
fn path_tree(tokens: &[(Token, usize)], at: &mut usize, prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
    let mut path = prefix;
    loop {
        match tokens.get(*at).map(|t| &t.0) {
            Some(Token::Ident(w)) if w == "self" && !path.is_empty() => *at += 1,
            Some(Token::Ident(w)) => {
                path.push(w.clone());
                *at += 1;
            }
            Some(Token::Punct('{')) => {
                *at += 1;
                loop {
                    match tokens.get(*at).map(|t| &t.0) {
                        Some(Token::Punct('}')) | None => {
                            *at += 1;
                            return;
                        }
                        Some(Token::Punct(',')) => *at += 1,
                        _ => {
                            let before = *at;
                            path_tree(tokens, at, path.clone(), out);
                            // a token no path starts with: step over it rather than stall
                            *at = (*at).max(before + 1);
                        }
                    }
                }
            }
            Some(Token::Punct('*')) => {
                *at += 1;
                out.push(path);
                return;
            }
            _ => {
                out.push(path);
                return;
            }
        }
        match tokens.get(*at).map(|t| &t.0) {
            Some(Token::PathSep) => *at += 1,
            Some(Token::Ident(w)) if w == "as" => {
                *at += 2;
                out.push(path);
                return;
            }
            _ => {
                out.push(path);
                return;
            }
        }
    }
}

/// The `crate::`/`super::` references of one file, written in module `module`.
fn references(file: &str, src: &str, module: &[String]) -> Vec<Reference> {
    let tokens = tokenize(src);
    let mut refs = Vec::new();
    // inline `mod name { ... }` blocks: (name, brace depth inside the block)
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut depth = 0;
    let mut i = 0;
    while i < tokens.len() {
        let (tok, line) = &tokens[i];
        match tok {
            Token::Punct('{') => depth += 1,
            Token::Punct('}') => {
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
                depth -= 1;
            }
            Token::Ident(w) if w == "mod" => {
                if let (Some((Token::Ident(name), _)), Some((Token::Punct('{'), _))) =
                    (tokens.get(i + 1), tokens.get(i + 2))
                {
                    if under_cfg_test(&tokens, i) {
                        // unit tests may build fixtures with a higher layer (a measured
                        // condition loaded through the CLI's reader, the reference engine
                        // beside the lanes): only the code that ships has to point one way
                        i = skip_block(&tokens, i + 2);
                        continue;
                    }
                    inline.push((name.clone(), depth + 1));
                    depth += 1;
                    i += 3;
                    continue;
                }
            }
            Token::Ident(w)
                if (w == "crate" || w == "super") && tokens.get(i + 1).map(|t| &t.0) == Some(&Token::PathSep) =>
            {
                // `$crate::` belongs to a macro's caller, `x::super::` cannot start a path
                let after_dollar = i > 0 && tokens[i - 1].0 == Token::Punct('$');
                let mid_path = i > 0 && tokens[i - 1].0 == Token::PathSep;
                if !after_dollar && !mid_path {
                    let here: Vec<String> =
                        module.iter().cloned().chain(inline.iter().map(|(n, _)| n.clone())).collect();
                    let mut at = i;
                    let mut paths = Vec::new();
                    path_tree(&tokens, &mut at, Vec::new(), &mut paths);
                    for p in paths {
                        if let Some(to) = resolve(&here, &p) {
                            refs.push(Reference { file: file.to_string(), line: *line, from: here.clone(), to });
                        }
                    }
                    i = at;
                    continue;
                }
            }
            _ => {}
        }
        i += 1;
    }
    refs
}

/// Whether the `mod` keyword at `tokens[at]` carries `#[cfg(test)]` among its attributes
/// (`pub`, `pub(crate)` may stand between).
fn under_cfg_test(tokens: &[(Token, usize)], at: usize) -> bool {
    let mut j = at;
    let ident = |k: usize, w: &str| matches!(&tokens[k].0, Token::Ident(x) if x == w);
    let punct = |k: usize, c: char| tokens[k].0 == Token::Punct(c);
    if j >= 1 && ident(j - 1, "pub") {
        j -= 1;
    } else if j >= 4 && punct(j - 1, ')') && punct(j - 3, '(') && ident(j - 4, "pub") {
        j -= 4;
    }
    // attributes, nearest first: `# [ ... ]`
    while j >= 1 && punct(j - 1, ']') {
        let close = j - 1;
        let mut k = close;
        let mut nest = 0;
        loop {
            if punct(k, ']') {
                nest += 1;
            } else if punct(k, '[') {
                nest -= 1;
                if nest == 0 {
                    break;
                }
            }
            if k == 0 {
                return false;
            }
            k -= 1;
        }
        let body: Vec<&Token> = tokens[k + 1..close].iter().map(|t| &t.0).collect();
        let cfg_test = [Token::Ident("cfg".into()), Token::Punct('('), Token::Ident("test".into()), Token::Punct(')')];
        if body.len() == 4 && body.iter().zip(&cfg_test).all(|(a, b)| *a == b) {
            return true;
        }
        if k == 0 || !punct(k - 1, '#') {
            return false;
        }
        j = k - 1;
    }
    false
}

/// The index just past the `}` that closes the `{` at `tokens[open]`.
fn skip_block(tokens: &[(Token, usize)], open: usize) -> usize {
    let mut nest = 0;
    for (k, (t, _)) in tokens.iter().enumerate().skip(open) {
        match t {
            Token::Punct('{') => nest += 1,
            Token::Punct('}') => {
                nest -= 1;
                if nest == 0 {
                    return k + 1;
                }
            }
            _ => {}
        }
    }
    tokens.len()
}

/// `crate::a::b` or `super::super::a` written in module `here`, as a path from the crate root.
fn resolve(here: &[String], path: &[String]) -> Option<Vec<String>> {
    let mut segs = path.iter().peekable();
    let mut base: Vec<String> = match segs.peek().map(|s| s.as_str()) {
        Some("crate") => {
            segs.next();
            Vec::new()
        }
        Some("super") => here.to_vec(),
        _ => return None,
    };
    while segs.peek().map(|s| s.as_str()) == Some("super") {
        segs.next();
        base.pop()?;
    }
    base.extend(segs.cloned());
    Some(base)
}

/// The file modules a file declares under `#[cfg(test)]` (`#[cfg(test)] mod tests;` in
/// `module`), as module paths.
fn test_file_modules(tokens: &[(Token, usize)], module: &[String]) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for i in 0..tokens.len().saturating_sub(2) {
        if let (Token::Ident(m), Token::Ident(name), Token::Punct(';')) =
            (&tokens[i].0, &tokens[i + 1].0, &tokens[i + 2].0)
        {
            if m == "mod" && under_cfg_test(tokens, i) {
                out.push(module.iter().cloned().chain([name.clone()]).collect());
            }
        }
    }
    out
}

/// The module a source file defines: src/lib.rs -> [], src/cli/mod.rs -> [cli],
/// src/cli/multi.rs -> [cli, multi].
fn file_module(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    let last = parts.pop().unwrap();
    let stem = last.trim_end_matches(".rs");
    if stem != "mod" && stem != "lib" {
        parts.push(stem.to_string());
    }
    parts
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// An edge between two sibling modules (children of `parent`), with the first place that
/// makes it.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Edge {
    parent: Vec<String>,
    from: String,
    to: String,
}

/// The sibling edges a set of references makes, given every module that exists (so that
/// `crate::cli::run`, a function of `cli`, is told apart from `crate::cli::study`, a module).
fn sibling_edges(refs: &[Reference], modules: &BTreeSet<Vec<String>>) -> BTreeMap<Edge, String> {
    let mut edges = BTreeMap::new();
    for r in refs {
        let common = r.from.iter().zip(&r.to).take_while(|(a, b)| a == b).count();
        if common >= r.from.len() || common >= r.to.len() {
            continue; // inside one module, a parent into its child, or a child into its parent
        }
        if !modules.contains(&r.to[..=common].to_vec()) {
            continue; // an item of the common parent
        }
        let edge = Edge { parent: r.to[..common].to_vec(), from: r.from[common].clone(), to: r.to[common].clone() };
        edges.entry(edge).or_insert_with(|| format!("{}:{} uses crate::{}", r.file, r.line, r.to.join("::")));
    }
    edges
}

/// Every import cycle, each named as a loop of modules with the place that makes each step.
fn cycles(edges: &BTreeMap<Edge, String>) -> Vec<String> {
    let mut by_parent: BTreeMap<&Vec<String>, BTreeMap<&str, Vec<&str>>> = BTreeMap::new();
    for e in edges.keys() {
        by_parent.entry(&e.parent).or_default().entry(&e.from).or_default().push(&e.to);
    }
    let mut found = Vec::new();
    let mut seen: BTreeSet<(Vec<String>, BTreeSet<String>)> = BTreeSet::new();
    for (parent, graph) in by_parent {
        for &start in graph.keys() {
            // shortest path from each successor back to `start`: a loop through `start`
            let mut prev: BTreeMap<&str, &str> = BTreeMap::new();
            let mut queue = std::collections::VecDeque::from([start]);
            let mut closed = None;
            while let Some(n) = queue.pop_front() {
                for &m in graph.get(n).into_iter().flatten() {
                    if m == start {
                        closed = Some(n);
                        break;
                    }
                    if !prev.contains_key(m) {
                        prev.insert(m, n);
                        queue.push_back(m);
                    }
                }
                if closed.is_some() {
                    break;
                }
            }
            let Some(mut last) = closed else { continue };
            let mut loop_nodes = vec![start];
            let mut back = vec![last];
            while last != start {
                last = prev[last];
                if last != start {
                    back.push(last);
                }
            }
            loop_nodes.extend(back.into_iter().rev());
            let key = (parent.clone(), loop_nodes.iter().map(|s| s.to_string()).collect());
            if !seen.insert(key) {
                continue; // the same loop, found from another of its modules
            }
            let scope = if parent.is_empty() { "crate".to_string() } else { format!("crate::{}", parent.join("::")) };
            let mut text = format!("import cycle among the modules of {scope}: {} -> {start}", loop_nodes.join(" -> "));
            for w in loop_nodes.windows(2).chain(std::iter::once(&[*loop_nodes.last().unwrap(), start][..])) {
                let edge = Edge { parent: parent.clone(), from: w[0].to_string(), to: w[1].to_string() };
                text += &format!("\n    {} -> {}: {}", w[0], w[1], edges[&edge]);
            }
            found.push(text);
        }
    }
    found
}

/// Top-level edges that point up the declared layer order, or name a module the order lacks.
fn layer_violations(
    edges: &BTreeMap<Edge, String>,
    modules: &BTreeSet<Vec<String>>,
    layers: &[&[&str]],
) -> Vec<String> {
    let rank = |m: &str| layers.iter().position(|l| l.contains(&m));
    let mut found = Vec::new();
    for m in modules.iter().filter(|m| m.len() == 1) {
        if rank(&m[0]).is_none() {
            found.push(format!("top-level module `{}` has no place in LAYERS (tests/layers.rs)", m[0]));
        }
    }
    for (e, place) in edges.iter().filter(|(e, _)| e.parent.is_empty()) {
        if let (Some(a), Some(b)) = (rank(&e.from), rank(&e.to)) {
            if b > a {
                found.push(format!(
                    "`{}` (layer {a}) uses `{}` (layer {b}), which sits above it: {place}",
                    e.from, e.to
                ));
            }
        }
    }
    found
}

/// References and module set of the crate in `src/`.
fn crate_graph(src: &Path) -> (Vec<Reference>, BTreeSet<Vec<String>>) {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let mut refs = Vec::new();
    let mut modules = BTreeSet::new();
    let mut sources = Vec::new();
    for f in files {
        let rel = f.strip_prefix(src).unwrap().to_path_buf();
        if rel == Path::new("main.rs") || rel.starts_with("bin") {
            continue; // binaries are crates of their own, over the library
        }
        let text = std::fs::read_to_string(&f).unwrap();
        sources.push((rel, text));
    }
    // unit tests in a file of their own (`#[cfg(test)] mod tests;`) are left out like inline ones
    let test_files: Vec<Vec<String>> =
        sources.iter().flat_map(|(rel, text)| test_file_modules(&tokenize(text), &file_module(rel))).collect();
    for (rel, text) in sources {
        let rel = rel.as_path();
        let module = file_module(rel);
        if test_files.iter().any(|t| module.starts_with(t)) {
            continue;
        }
        let name = format!("src/{}", rel.display());
        // inline modules exist as well as file modules
        let tokens = tokenize(&text);
        for w in tokens.windows(3) {
            if let (Token::Ident(m), Token::Ident(n), Token::Punct('{')) = (&w[0].0, &w[1].0, &w[2].0) {
                if m == "mod" {
                    modules.insert(module.iter().cloned().chain([n.clone()]).collect());
                }
            }
        }
        for i in 1..=module.len() {
            modules.insert(module[..i].to_vec());
        }
        refs.extend(references(&name, &text, &module));
    }
    (refs, modules)
}

#[test]
fn no_two_modules_import_each_other_directly_or_in_a_loop() {
    let (refs, modules) = crate_graph(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    assert!(refs.len() > 100, "the parser found only {} crate paths: it no longer reads the source", refs.len());
    let edges = sibling_edges(&refs, &modules);
    let found = cycles(&edges);
    assert!(found.is_empty(), "{}", found.join("\n"));
}

#[test]
fn top_level_modules_use_only_their_own_layer_or_below() {
    let (refs, modules) = crate_graph(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    let found = layer_violations(&sibling_edges(&refs, &modules), &modules, LAYERS);
    assert!(found.is_empty(), "{}", found.join("\n"));
}

/// The `sawtooth::` paths of the Python package's source.
fn python_paths() -> Vec<Vec<String>> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("python/src/lib.rs");
    let tokens = tokenize(&std::fs::read_to_string(&path).unwrap());
    let mut paths = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        let starts = matches!(&tokens[i].0, Token::Ident(w) if w == "sawtooth")
            && tokens.get(i + 1).map(|t| &t.0) == Some(&Token::PathSep)
            && (i == 0 || tokens[i - 1].0 != Token::PathSep);
        if starts {
            path_tree(&tokens, &mut i, Vec::new(), &mut paths);
        } else {
            i += 1;
        }
    }
    paths
}

#[test]
fn python_resolves_scenarios_through_the_library_not_the_cli_flags() {
    // both front ends build a scenario_request::ScenarioRequest; the clap structs are the CLI's
    let paths = python_paths();
    assert!(paths.iter().any(|p| p.starts_with(&strings(&["sawtooth", "scenario_request"]))), "{paths:?}");
    let into_args: Vec<_> = paths.iter().filter(|p| p.starts_with(&strings(&["sawtooth", "cli", "args"]))).collect();
    assert!(into_args.is_empty(), "python/src/lib.rs uses the CLI's flag structs: {into_args:?}");
}

// ---- the checker's own specification, on small synthetic sources and graphs ----

fn strings(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

fn refs_of(src: &str, module: &[&str]) -> Vec<Vec<String>> {
    references("x.rs", src, &strings(module)).into_iter().map(|r| r.to).collect()
}

#[test]
fn use_trees_expand_into_every_path_they_name() {
    let got = refs_of("use crate::{a::b, c::{self, d as e, f::*}};\n", &["m"]);
    assert_eq!(got, vec![strings(&["a", "b"]), strings(&["c"]), strings(&["c", "d"]), strings(&["c", "f"])]);
}

#[test]
fn super_resolves_against_the_file_and_its_inline_modules() {
    // in src/cli/multi.rs: super:: is cli; inside `mod tests { }` it is multi itself
    let src = "use super::study::Plan;\nmod tests { use super::*; fn t() { super::super::sweep::run(); } }\nfn f() { super::x(); }";
    let got = refs_of(src, &["cli", "multi"]);
    assert_eq!(
        got,
        vec![
            strings(&["cli", "study", "Plan"]),
            strings(&["cli", "multi"]),
            strings(&["cli", "sweep", "run"]),
            strings(&["cli", "x"])
        ]
    );
}

#[test]
fn qualified_paths_in_code_count_and_comments_strings_and_macros_do_not() {
    let src = r##"
        // crate::commented::Out
        /* crate::block /* nested crate::deeper */ crate::still_comment */
        const S: &str = "crate::in_string";
        const R: &str = r#"crate::"raw" string"#;
        macro_rules! m { () => { $crate::macro_path::X }; }
        fn f<'a>(x: &'a str) -> char { let _ = crate::engine::cpu::Cpu::<f64>::new(); 'c' }
        pub(crate) fn g() { let _ = crate::fit::Param::Mu; }
    "##;
    assert_eq!(refs_of(src, &["m"]), vec![strings(&["engine", "cpu", "Cpu"]), strings(&["fit", "Param", "Mu"])]);
}

#[test]
fn unit_test_modules_are_left_out_and_the_code_after_them_is_not() {
    let src = "#[cfg(test)]\nmod tests { use crate::cli::x; mod deeper { use crate::cli::y; } }\n\
               #[cfg(test)]\n#[allow(dead_code)]\npub(crate) mod more { use crate::cli::z; }\n\
               mod inner { use super::super::fit::Param; }\nuse crate::model::Design;";
    assert_eq!(
        refs_of(src, &["calibrate", "solver"]),
        vec![strings(&["calibrate", "fit", "Param"]), strings(&["model", "Design"])]
    );
}

#[test]
fn unit_test_files_are_found_and_other_file_modules_are_not() {
    let src = "#[cfg(test)]\nmod tests;\nmod search;\npub(crate) mod inner;\n#[cfg(test)]\npub(crate) mod fixtures;";
    assert_eq!(
        test_file_modules(&tokenize(src), &strings(&["engine", "lanes"])),
        vec![strings(&["engine", "lanes", "tests"]), strings(&["engine", "lanes", "fixtures"])]
    );
}

#[test]
fn lines_are_counted_through_multiline_comments_and_strings() {
    let src = "/* one\ntwo */\nconst S: &str = \"a\nb\";\nuse crate::x::Y;\n";
    let r = references("x.rs", src, &[]);
    assert_eq!(r[0].line, 5);
}

fn synthetic(edges: &[(&str, &str, &str)]) -> (BTreeMap<Edge, String>, BTreeSet<Vec<String>>) {
    // (from-module, to-module, item): every module is top-level or under `cli`
    let path = |m: &str| strings(&m.split("::").collect::<Vec<_>>());
    let mut modules = BTreeSet::new();
    let refs: Vec<Reference> = edges
        .iter()
        .map(|(from, to, item)| {
            for m in [from, to] {
                let p = path(m);
                for i in 1..=p.len() {
                    modules.insert(p[..i].to_vec());
                }
            }
            let mut to = path(to);
            to.push(item.to_string());
            Reference { file: format!("src/{from}.rs"), line: 1, from: path(from), to }
        })
        .collect();
    (sibling_edges(&refs, &modules), modules)
}

#[test]
fn a_direct_cycle_between_top_level_modules_is_named() {
    let (edges, _) =
        synthetic(&[("calibrate", "fit", "Param"), ("fit", "calibrate", "solve"), ("fit", "model", "Design")]);
    let found = cycles(&edges);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].contains("calibrate -> fit -> calibrate"), "{}", found[0]);
    assert!(found[0].contains("src/calibrate.rs:1 uses crate::fit::Param"), "{}", found[0]);
}

#[test]
fn a_loop_through_three_sibling_submodules_is_named_once() {
    let (edges, _) = synthetic(&[
        ("cli::multi", "cli::study", "Plan"),
        ("cli::study", "cli::sweep", "grid"),
        ("cli::sweep", "cli::multi", "members"),
        ("cli::multi", "model", "Design"),
    ]);
    let found = cycles(&edges);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(
        found[0].starts_with("import cycle among the modules of crate::cli: multi -> study -> sweep -> multi"),
        "{}",
        found[0]
    );
}

#[test]
fn one_way_graphs_and_parent_child_references_pass() {
    let (edges, _) = synthetic(&[
        ("fit", "calibrate", "Param"),
        ("diagnose", "calibrate", "Target"),
        ("diagnose", "fit", "report"),
        ("cli", "cli::study", "run"),
        ("cli::study", "cli", "Args"),
    ]);
    assert!(cycles(&edges).is_empty(), "{:?}", cycles(&edges));
}

#[test]
fn an_upward_edge_and_an_unplaced_module_break_the_layer_order() {
    let (edges, modules) =
        synthetic(&[("model", "engine", "Cpu"), ("engine", "model", "Design"), ("stray", "model", "Design")]);
    let found = layer_violations(&edges, &modules, &[&["model"], &["engine"]]);
    assert!(found.iter().any(|f| f.starts_with("`model` (layer 0) uses `engine` (layer 1)")), "{found:?}");
    assert!(found.iter().any(|f| f.contains("`stray` has no place in LAYERS")), "{found:?}");
    assert_eq!(found.len(), 2, "{found:?}");
}
