//! Every `sawtooth` command written in README.md, BENCHMARKS.md and the pages of docs/ is one
//! the command line accepts: its subcommand, flags and values parse (clap's rules; the checks
//! a command makes once it runs, such as `--pop` against the algorithm, are the commands' own
//! tests'). A renamed or removed flag fails here instead of in a new user's terminal. And
//! every relative link between those pages leads to a file that exists.

use clap::Parser;
use sawtooth::cli::Cli;

/// The commands in the shell blocks of a Markdown file: continuation lines joined, comments
/// dropped, and whatever runs the binary (`cargo run --release --`, `$S`, `$st`, a path to
/// it) replaced by its name. Returns (line number, the words after the binary).
fn documented_commands(file: &str) -> Vec<(usize, Vec<String>)> {
    let text = std::fs::read_to_string(format!("{}/{file}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let mut commands = Vec::new();
    let (mut in_shell, mut pending, mut start) = (false, String::new(), 0);
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim();
        if let Some(lang) = trimmed.strip_prefix("```") {
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
        let joined = std::mem::take(&mut pending);
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
    for page in ["README.md".to_string(), "BENCHMARKS.md".to_string()].into_iter().chain(docs_pages()) {
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
