//! Every `sawtooth` command written in README.md, BENCHMARKS.md and the pages of docs/ is one
//! the command line accepts: its subcommand, flags and values parse (clap's rules; the checks
//! a command makes once it runs, such as `--pop` against the algorithm, are the commands' own
//! tests'). A renamed or removed flag fails here instead of in a new user's terminal. Every
//! cargo target those pages name (`--test X`, `--bench X`, `--example X`, `-p PKG`, and the
//! test filters of `--test suite`, which must name a module of tests/suite.rs) and every
//! script (`scripts/...`) exists. And every relative link between those pages leads to a
//! file that exists.

use clap::Parser;
use sawtooth::cli::Cli;

/// The commands in the shell blocks of a Markdown file: continuation lines joined, comments
/// dropped, and whatever runs the binary (`cargo run --release --`, `$S`, `$st`, a path to
/// it) replaced by its name. Returns (line number, the words after the binary).
fn documented_commands(file: &str) -> Vec<(usize, Vec<String>)> {
    let text = std::fs::read_to_string(format!("{}/{file}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let mut commands = Vec::new();
    for (start, joined) in shell_lines(&text) {
        for runner in ["cargo run --release -- ", "$S ", "$st ", "target/release/sawtooth ", "sawtooth "] {
            // the command starts the line, or follows `time`, `&&`, `;` or `$(`
            let Some(at) = joined.find(runner) else { continue };
            let before = joined[..at].trim_end();
            let starts_command = before.is_empty()
                || before.ends_with("&&")
                || before.ends_with(';')
                || before.ends_with("$(")
                || before.ends_with("./")
                || before.ends_with("time")
                || before.ends_with("%e s wall\"")
                || before.ends_with("do")
                // environment assignments before the command: `SAWTOOTH_PROFILE=1 cargo run …`
                || (joined[..at].ends_with(' ')
                    && before.split_whitespace().all(|w| w.split_once('=').is_some_and(|(k, v)| is_env_name(k) && !v.is_empty())));
            if !starts_command {
                continue;
            }
            let rest = &joined[at + runner.len()..];
            let rest = rest.split(['|', ')', ';']).next().unwrap().split(" && ").next().unwrap();
            commands.push((start, words(rest)));
            break;
        }
    }
    commands
}

/// The command lines of a Markdown page's shell blocks (```sh, ```bash): continuation lines
/// joined, comments dropped. Returns (the line the command starts on, the command).
fn shell_lines(text: &str) -> Vec<(usize, String)> {
    let mut lines = Vec::new();
    let (mut in_shell, mut pending, mut start) = (false, String::new(), 0);
    for (i, line) in text.lines().enumerate() {
        if let Some(lang) = line.trim().strip_prefix("```") {
            in_shell = !in_shell && (lang == "sh" || lang == "bash");
            continue;
        }
        if !in_shell {
            continue;
        }
        if pending.is_empty() {
            start = i + 1;
        }
        let code = strip_comment(line);
        if let Some(head) = code.trim_end().strip_suffix('\\') {
            pending.push_str(head);
            pending.push(' ');
            continue;
        }
        pending.push_str(&code);
        lines.push((start, std::mem::take(&mut pending)));
    }
    lines
}

/// The inline code spans of a page's prose (outside fenced blocks), each with the line it
/// starts on; a span may wrap onto the next line of its paragraph.
fn inline_code(text: &str) -> Vec<(usize, String)> {
    let mut spans = Vec::new();
    let (mut fenced, mut paragraph, mut first_line) = (false, String::new(), 0);
    let mut end_paragraph = |paragraph: &mut String, first_line: usize| {
        let text = std::mem::take(paragraph);
        let mut offset = 0;
        for (k, piece) in text.split('`').enumerate() {
            if k % 2 == 1 {
                spans.push((first_line + text[..offset].matches('\n').count(), piece.replace('\n', " ")));
            }
            offset += piece.len() + 1;
        }
    };
    for (i, line) in text.lines().enumerate() {
        let fence = line.trim().starts_with("```");
        if fence || (!fenced && line.trim().is_empty()) {
            end_paragraph(&mut paragraph, first_line);
            fenced ^= fence;
        } else if !fenced {
            if paragraph.is_empty() {
                first_line = i + 1;
            }
            paragraph.push_str(line);
            paragraph.push('\n');
        }
    }
    end_paragraph(&mut paragraph, first_line);
    spans
}

/// A shell variable's name: letters, digits and underscores, not starting with a digit.
fn is_env_name(k: &str) -> bool {
    !k.is_empty()
        && !k.starts_with(|c: char| c.is_ascii_digit())
        && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// A line without its `#` comment (a `#` that starts a word, outside quotes).
fn strip_comment(line: &str) -> String {
    let mut out = String::new();
    let (mut quote, mut prev_space) = (None, true);
    for c in line.chars() {
        match (quote, c) {
            (None, '#') if prev_space => break,
            (None, '"' | '\'') => quote = Some(c),
            (Some(q), _) if c == q => quote = None,
            _ => {}
        }
        prev_space = c.is_whitespace();
        out.push(c);
    }
    out
}

/// Shell words: whitespace-separated, quotes removed, variables given example values.
fn words(command: &str) -> Vec<String> {
    let mut out = Vec::new();
    let (mut word, mut quote, mut any) = (String::new(), None, false);
    for c in command.chars() {
        match (quote, c) {
            (None, '"' | '\'') => {
                quote = Some(c);
                any = true;
            }
            (Some(q), _) if c == q => quote = None,
            (None, c) if c.is_whitespace() => {
                if any {
                    out.push(std::mem::take(&mut word));
                    any = false;
                }
            }
            _ => {
                word.push(c);
                any = true;
            }
        }
    }
    if any {
        out.push(word);
    }
    out.into_iter()
        .map(|w| w.replace("$USER", "user").replace("${env}", "lunar").replace("$env", "lunar").replace("$jid", "1"))
        .collect()
}

fn check(file: &str, at_least: usize) {
    let commands = documented_commands(file);
    assert!(commands.len() >= at_least, "{file}: found only {} commands: {commands:?}", commands.len());
    eprintln!("{file}: {} commands", commands.len());
    let mut failures = Vec::new();
    for (line, args) in &commands {
        if let Err(e) = Cli::try_parse_from(std::iter::once("sawtooth".to_string()).chain(args.iter().cloned())) {
            // `--help` and `--version` are answers, not errors
            if e.use_stderr() {
                failures.push(format!("{file}:{line}: sawtooth {}\n{}", args.join(" "), e.render()));
            }
        }
    }
    assert!(failures.is_empty(), "documented commands the CLI refuses:\n{}", failures.join("\n"));
}

/// The Markdown pages of docs/, by path relative to the repository's root.
fn docs_pages() -> Vec<String> {
    let dir = format!("{}/docs", env!("CARGO_MANIFEST_DIR"));
    let mut pages: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".md"))
        .map(|n| format!("docs/{n}"))
        .collect();
    pages.sort();
    pages
}

#[test]
fn every_command_in_the_readme_parses() {
    check("README.md", 8);
}

#[test]
fn every_command_in_the_docs_pages_parses() {
    let pages = docs_pages();
    // the workflow pages the README's index links to, each with commands of its own
    for page in ["simulate", "calibrate-and-diagnose", "optimise", "campaigns", "engines", "physics"] {
        let path = format!("docs/{page}.md");
        assert!(pages.contains(&path), "{path} is missing: {pages:?}");
        check(&path, 1);
    }
    for page in &pages {
        check(page, 0);
    }
    let total: usize = pages.iter().map(|p| documented_commands(p).len()).sum();
    assert!(total >= 30, "the docs pages hold only {total} commands");
}

/// The relative links of a Markdown file (`[text](target)` and `[text](target#anchor)`) as
/// (target, anchor): web addresses left out; a link within the page has an empty target.
fn relative_links(text: &str) -> Vec<(String, Option<String>)> {
    let mut links = Vec::new();
    for (at, _) in text.match_indices("](") {
        let rest = &text[at + 2..];
        let Some(end) = rest.find(')') else { continue };
        let (target, anchor) = match rest[..end].split_once('#') {
            Some((t, a)) => (t, Some(a.to_string())),
            None => (&rest[..end], None),
        };
        if (target.is_empty() && anchor.is_none()) || target.contains("://") || target.starts_with("mailto:") {
            continue;
        }
        links.push((target.to_string(), anchor));
    }
    links
}

/// The anchors GitHub gives a Markdown page's headings: the heading's text in lower case,
/// every character but letters, digits, `-` and `_` dropped and each space made a `-`
/// (`## Effects beyond the thesis's model` is `#effects-beyond-the-thesiss-model`); a
/// heading repeated gets `-1`, `-2`, ... Lines in code blocks are not headings.
fn heading_anchors(text: &str) -> Vec<String> {
    let mut anchors = Vec::new();
    let mut seen = std::collections::HashMap::<String, usize>::new();
    let mut in_code = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
            continue;
        }
        let Some(title) = line.strip_prefix('#').map(|t| t.trim_start_matches('#')) else { continue };
        if in_code || !title.starts_with(' ') {
            continue;
        }
        let slug: String = title
            .trim()
            .to_lowercase()
            .chars()
            .filter_map(|c| match c {
                ' ' => Some('-'),
                c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
                _ => None,
            })
            .collect();
        let n = seen.entry(slug.clone()).or_insert(0);
        anchors.push(if *n == 0 { slug } else { format!("{slug}-{n}") });
        *n += 1;
    }
    anchors
}

#[test]
fn every_relative_link_leads_to_a_file_and_its_anchor_to_a_heading() {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut broken = Vec::new();
    let (mut seen, mut anchored) = (0, 0);
    for page in all_pages() {
        let path = root.join(&page);
        let text = std::fs::read_to_string(&path).unwrap();
        for (target, anchor) in relative_links(&text) {
            seen += 1;
            let file = if target.is_empty() { path.clone() } else { path.parent().unwrap().join(&target) };
            if !file.exists() {
                broken.push(format!("{page}: {target} (no such file)"));
                continue;
            }
            let Some(anchor) = anchor else { continue };
            anchored += 1;
            let headings = heading_anchors(&std::fs::read_to_string(&file).unwrap_or_default());
            if !headings.contains(&anchor) {
                broken.push(format!("{page}: {target}#{anchor} (no such heading; {target} has {headings:?})"));
            }
        }
    }
    assert!(
        seen >= 20 && anchored >= 3,
        "only {seen} relative links ({anchored} with an anchor) found: the extraction is broken"
    );
    assert!(broken.is_empty(), "links that lead nowhere:\n{}", broken.join("\n"));
}

#[test]
fn every_command_in_the_benchmarks_parses() {
    check("BENCHMARKS.md", 8);
}

#[test]
fn the_extraction_sees_continuations_comments_and_quotes() {
    assert_eq!(strip_comment("a --b 'x # y' # note"), "a --b 'x # y' ");
    assert_eq!(words("simulate --plot 'a b.svg' --env $env"), ["simulate", "--plot", "a b.svg", "--env", "lunar"]);
    assert!(is_env_name("SAWTOOTH_PROFILE") && !is_env_name("--flag") && !is_env_name("1X"));
    let some = |t: &str, a: Option<&str>| (t.to_string(), a.map(str::to_string));
    assert_eq!(
        relative_links("[a](docs/x.md#y), [b](https://e.org), [c](#z), ![f](figures/p.png)"),
        [some("docs/x.md", Some("y")), some("", Some("z")), some("figures/p.png", None)]
    );
    let page = "# Top\n## Effects beyond the thesis's model, and `synth`\n```sh\n# not a heading\n```\n## Top\n#tag\n";
    assert_eq!(heading_anchors(page), ["top", "effects-beyond-the-thesiss-model-and-synth", "top-1"]);
    // and a refused flag is caught: the check can fail
    let bad = Cli::try_parse_from(["sawtooth", "simulate", "--no-such-flag"]);
    assert!(bad.is_err_and(|e| e.use_stderr()));
}

/// The pages whose targets, scripts and links are checked.
fn all_pages() -> Vec<String> {
    ["README.md", "BENCHMARKS.md", "CHANGELOG.md"].map(String::from).into_iter().chain(docs_pages()).collect()
}

/// The cargo invocations a Markdown page shows, in its shell blocks and in the inline code
/// of its prose. Returns (line number, the words after `cargo`).
fn cargo_invocations(text: &str) -> Vec<(usize, Vec<String>)> {
    let mut invocations = Vec::new();
    for (line, snippet) in shell_lines(text).into_iter().chain(inline_code(text)) {
        for command in snippet.replace("&&", ";").split(['|', ';', '(', ')']) {
            let w = words(command);
            if let Some(at) = w.iter().position(|x| x == "cargo") {
                invocations.push((line, w[at + 1..].to_vec()));
            }
        }
    }
    invocations
}

/// The workspace's packages by name, each with its test, bench and example targets: those
/// its manifest names and those cargo finds by itself (`tests/*.rs`, `benches/*.rs`,
/// `examples/*.rs`) unless the manifest turns that off.
fn cargo_targets() -> std::collections::BTreeMap<String, [std::collections::BTreeSet<String>; 3]> {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let read = |dir: &std::path::Path| -> toml::Table {
        std::fs::read_to_string(dir.join("Cargo.toml")).unwrap().parse().unwrap()
    };
    let workspace = read(&root);
    let members = workspace["workspace"]["members"].as_array().unwrap();
    let mut packages = std::collections::BTreeMap::new();
    for member in members {
        let dir = root.join(member.as_str().unwrap());
        let manifest = read(&dir);
        let package = manifest["package"].as_table().unwrap();
        let mut targets: [std::collections::BTreeSet<String>; 3] = Default::default();
        for (k, (kind, auto, folder)) in [
            ("test", "autotests", "tests"),
            ("bench", "autobenches", "benches"),
            ("example", "autoexamples", "examples"),
        ]
        .into_iter()
        .enumerate()
        {
            for target in manifest.get(kind).and_then(|t| t.as_array()).into_iter().flatten() {
                targets[k].insert(target["name"].as_str().unwrap().to_string());
            }
            let auto = package.get(auto).and_then(|a| a.as_bool()).unwrap_or(true);
            for entry in std::fs::read_dir(dir.join(folder)).into_iter().flatten().filter(|_| auto) {
                let path = entry.unwrap().path();
                if path.extension().is_some_and(|e| e == "rs") {
                    targets[k].insert(path.file_stem().unwrap().to_str().unwrap().to_string());
                }
            }
        }
        packages.insert(package["name"].as_str().unwrap().to_string(), targets);
    }
    packages
}

/// The modules of the one integration-test binary (`mod NAME;` in tests/suite.rs) and the
/// names of the test functions in tests/: what a test filter of `--test suite` can match.
fn suite_names() -> (Vec<String>, Vec<String>) {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests");
    let suite = std::fs::read_to_string(dir.join("suite.rs")).unwrap();
    let modules =
        suite.lines().filter_map(|l| l.trim().strip_prefix("mod ")?.strip_suffix(';').map(str::to_string)).collect();
    let mut functions = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "rs") {
            let text = std::fs::read_to_string(&path).unwrap();
            for (at, _) in text.match_indices("fn ") {
                let name: String =
                    text[at + 3..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
                functions.push(name);
            }
        }
    }
    (modules, functions)
}

/// A word that stands for something the reader fills in (`NAME::`, `<target>`, `$DIR`).
fn is_placeholder(word: &str) -> bool {
    word.contains(['<', '$'])
        || (word.chars().any(|c| c.is_ascii_uppercase())
            && word.chars().all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_' || c == ':'))
}

/// What is wrong with one cargo invocation (the words after `cargo`): a package, test, bench
/// or example target that does not exist, or a filter of `--test suite` that names no module
/// of the suite (and, without `::`, no module or test function either).
fn cargo_problems(
    args: &[String],
    packages: &std::collections::BTreeMap<String, [std::collections::BTreeSet<String>; 3]>,
    (modules, functions): &(Vec<String>, Vec<String>),
) -> Vec<String> {
    let mut problems = Vec::new();
    let Some(subcommand) = args.first() else { return problems };
    let (mut package, mut named, mut filters, mut lib) = ("sawtooth".to_string(), Vec::new(), Vec::new(), false);
    let mut i = 1;
    let mut harness = false;
    while i < args.len() {
        let word = &args[i];
        i += 1;
        let (flag, inline) = match word.split_once('=') {
            Some((f, v)) if f.starts_with('-') => (f, Some(v.to_string())),
            _ => (word.as_str(), None),
        };
        let takes_value = if harness {
            ["--test-threads", "--skip", "--format", "--color", "--logfile", "-Z", "--shuffle-seed"].contains(&flag)
        } else {
            [
                "--test",
                "--bench",
                "--example",
                "--bin",
                "-p",
                "--package",
                "--config",
                "--target",
                "--features",
                "-F",
                "--profile",
                "-j",
                "--jobs",
                "--manifest-path",
                "--message-format",
                "--color",
                "--target-dir",
                "-Z",
                "--exclude",
                "-e",
                "--edges",
                "-i",
                "--invert",
                "--depth",
                "--format",
                "--prefix",
            ]
            .contains(&flag)
        };
        let value = if takes_value && inline.is_none() {
            i += 1;
            args.get(i - 1).cloned()
        } else {
            inline
        };
        match (harness, flag) {
            (false, "--") => harness = true,
            (false, "-p" | "--package") => package = value.unwrap_or_default(),
            (false, "--test") => named.push((0, value.unwrap_or_default())),
            (false, "--bench") => named.push((1, value.unwrap_or_default())),
            (false, "--example") => named.push((2, value.unwrap_or_default())),
            (false, "--lib") => lib = true,
            (true, "--skip") => filters.extend(value),
            (_, f) if !f.starts_with('-') && (subcommand == "test") => filters.push(word.clone()),
            _ => {}
        }
        if subcommand == "run" && harness {
            break; // the program's own arguments
        }
    }
    if is_placeholder(&package) {
        return problems;
    }
    let Some(targets) = packages.get(&package) else {
        problems.push(format!("no package `{package}` in the workspace ({:?})", packages.keys().collect::<Vec<_>>()));
        return problems;
    };
    for (kind, name) in &named {
        if !is_placeholder(name) && !targets[*kind].contains(name) {
            let what = ["test", "bench", "example"][*kind];
            problems.push(format!("`{package}` has no {what} target `{name}` (it has {:?})", targets[*kind]));
        }
    }
    // a filter of the one integration-test binary: `MODULE::` or `MODULE::test`, or a word
    // that some module or test function contains
    if named == [(0, "suite".to_string())] && !lib {
        for filter in filters.iter().filter(|f| !is_placeholder(f)) {
            let known = match filter.split_once("::") {
                Some((module, _)) => modules.contains(&module.to_string()),
                None => modules.iter().chain(functions).any(|n| n.contains(filter.as_str())),
            };
            if !known {
                problems.push(format!("the filter `{filter}` matches no module of tests/suite.rs ({modules:?})"));
            }
        }
    }
    problems
}

/// The paths under `scripts/` a page names (in code or prose), without trailing punctuation.
fn script_paths(text: &str) -> Vec<(usize, String)> {
    let mut paths = Vec::new();
    for (n, line) in text.lines().enumerate() {
        for (at, _) in line.match_indices("scripts/") {
            let before = line[..at].chars().next_back();
            if before.is_some_and(|c| c.is_ascii_alphanumeric() || "/._-".contains(c)) {
                continue; // part of a longer path (`../scripts/x` is a link, checked as one)
            }
            let path: String =
                line[at..].chars().take_while(|c| c.is_ascii_alphanumeric() || "/._-".contains(*c)).collect();
            let path = path.trim_end_matches('.');
            if path.len() > "scripts/".len() && !path.contains("...") {
                paths.push((n + 1, path.to_string()));
            }
        }
    }
    paths
}

#[test]
fn every_cargo_target_and_script_the_docs_name_exists() {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let (packages, names) = (cargo_targets(), suite_names());
    let mut failures = Vec::new();
    let (mut invocations, mut scripts) = (0, 0);
    for page in all_pages() {
        let text = std::fs::read_to_string(root.join(&page)).unwrap();
        for (line, args) in cargo_invocations(&text) {
            invocations += 1;
            for problem in cargo_problems(&args, &packages, &names) {
                failures.push(format!("{page}:{line}: cargo {}: {problem}", args.join(" ")));
            }
        }
        for (line, path) in script_paths(&text) {
            scripts += 1;
            if !root.join(&path).exists() {
                failures.push(format!("{page}:{line}: {path}: no such file"));
            }
        }
    }
    assert!(invocations >= 20 && scripts >= 10, "only {invocations} cargo commands and {scripts} scripts found");
    assert!(failures.is_empty(), "documented targets that do not exist:\n{}", failures.join("\n"));
}

#[test]
fn the_target_check_refuses_what_does_not_exist() {
    let (packages, names) = (cargo_targets(), suite_names());
    let problems = |command: &str| {
        let spans = cargo_invocations(command);
        assert_eq!(spans.len(), 1, "{command}: {spans:?}");
        cargo_problems(&spans[0].1, &packages, &names)
    };
    // the integration tests are one binary: a file of tests/ is a module, not a target
    assert_eq!(problems("A run (`cargo test --release --locked --test\nfuzz_readers`: 1.7 s).").len(), 1);
    assert!(problems("`cargo test --release --locked --test suite fuzz_readers:: -- --nocapture --test-threads 1`")
        .is_empty());
    assert!(problems("`cargo test --test suite -- layers:: twins::sled --test-threads=1`").is_empty());
    assert_eq!(problems("`cargo test --test suite no_such_module::`").len(), 1);
    assert_eq!(problems("`cargo test --test suite -- twins:: gone::`").len(), 1);
    assert!(problems("`cargo test --release --test suite NAME::`").is_empty());
    assert!(problems("```sh\ncargo bench -p sawtooth-benches --bench engines -- prepare\n```").is_empty());
    assert_eq!(problems("```sh\ncargo bench -p sawtooth-benches --bench engine\n```").len(), 1);
    assert_eq!(problems("```sh\ncargo bench -p sawtooth-bench --bench engines\n```").len(), 1);
    assert!(problems("```sh\ncargo run --release --example engine_digest 300\n```").is_empty());
    assert_eq!(problems("```sh\nX=1 cargo run --release --example no_such_example -- --test gone\n```").len(), 1);
    assert_eq!(
        script_paths("run `scripts/test.sh`, then scripts/gpu-table.sh. Not ../scripts/x.sh"),
        [(1, "scripts/test.sh".to_string()), (1, "scripts/gpu-table.sh".to_string())]
    );
}
