//! The docs check: every command in README.md and the guide (`docs/*.md`) still works, so
//! none rots.
//!
//! Fenced ```sh blocks are read line by line (continuations joined, comments dropped,
//! `&&` chains split), in order, each file in a working folder of its own that links the
//! repository's folders (so `scenes/...` and `data/...` resolve and outputs stay out of
//! the clone):
//! - `target/release/arbvis ARGS` (and `cargo run ... -- ARGS`, the main job) run this
//!   build's binary with ARGS and must succeed. `view`, `bench` and `study` (a window, or
//!   minutes of work), and every command of a block after `<!-- docs-check: dry-run -->`
//!   (data that must be downloaded first), run with `--dry-run`: flags parsed, the scene
//!   loaded, the files it reads found (or, for a scene whose `data_from` says how to
//!   download them, the error naming the missing file and the download).
//! - `python3 benches/SCRIPT.py ARGS`: the script exists and knows every `--flag` and
//!   word given (they need VTK or a download; `benches/` runs them).
//! - `cargo ...`, `bash scripts/...`, `pip install ...`: setup the CI itself runs; a
//!   `--test NAME` or `--example NAME` must exist.
//! - `head -c N /dev/urandom > FILE` runs as written; any other command fails the check
//!   until it is taught here.
//!
//! Inline code spans in prose that start with `arbvis ` or `target/release/arbvis `, with
//! arguments and no `...` or placeholder (`SCENE`), run with `--dry-run` too.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{copy_tree, temp_dir};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The markdown files the check reads.
fn documents() -> Vec<PathBuf> {
    let mut files = vec![root().join("README.md")];
    let mut guide: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    guide.sort();
    files.extend(guide);
    files
}

/// One command of a ```sh block: where it is and what it says.
struct Line {
    file: String,
    number: usize,
    text: String,
    dry_run: bool,
}

/// The commands of every ```sh block of `text`.
fn sh_commands(file: &str, text: &str) -> Vec<Line> {
    let mut out = Vec::new();
    let mut in_sh = false;
    let mut in_other = false;
    let mut dry_block = false;
    let mut dry_next = false;
    let mut pending: Option<(usize, String)> = None;
    for (i, raw) in text.lines().enumerate() {
        let trimmed = raw.trim();
        if !in_sh && !in_other {
            if trimmed == "<!-- docs-check: dry-run -->" {
                dry_next = true;
            } else if trimmed == "```sh" {
                in_sh = true;
                dry_block = dry_next;
                dry_next = false;
            } else if trimmed.starts_with("```") {
                in_other = true;
            }
            continue;
        }
        if in_other {
            in_other = !trimmed.starts_with("```");
            continue;
        }
        if trimmed.starts_with("```") {
            in_sh = false;
            continue;
        }
        let code = strip_comment(raw);
        let (start, mut joined) = pending.take().unwrap_or((i + 1, String::new()));
        if let Some(head) = code.trim_end().strip_suffix('\\') {
            joined.push_str(head.trim());
            joined.push(' ');
            pending = Some((start, joined));
            continue;
        }
        joined.push_str(code.trim());
        for part in joined.split("&&") {
            let part = part.trim();
            if !part.is_empty() {
                out.push(Line {
                    file: file.to_string(),
                    number: start,
                    text: part.to_string(),
                    dry_run: dry_block,
                });
            }
        }
    }
    out
}

/// `line` without a trailing `# comment` (a `#` outside quotes, after a space or at the start).
fn strip_comment(line: &str) -> &str {
    let mut quote = None;
    let mut previous = ' ';
    for (i, c) in line.char_indices() {
        match (quote, c) {
            (None, '"' | '\'') => quote = Some(c),
            (Some(q), _) if c == q => quote = None,
            (None, '#') if previous.is_whitespace() => return &line[..i],
            _ => {}
        }
        previous = c;
    }
    line
}

/// Shell-like words: whitespace-separated, quotes grouping and removed.
fn words(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut word = String::new();
    let mut quote = None;
    let mut any = false;
    for c in text.chars() {
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
    out
}

/// The repository's own top-level entries that the documents' commands read. Only these are
/// linked into a working folder: whatever else a user's clone holds (the `f3.zarr` or
/// `product.png` that following the README leaves) must not change what a command does.
const REPOSITORY_ENTRIES: [&str; 12] = [
    "ARCHITECTURE.md",
    "Cargo.lock",
    "Cargo.toml",
    "README.md",
    "benches",
    "crates",
    "data",
    "docs",
    "examples",
    "programs",
    "scripts",
    "src",
];

/// A working folder for one document: links to the repository's own folders, so relative
/// paths resolve as from the clone while outputs land here.
fn workdir(name: &str) -> PathBuf {
    let dir = temp_dir(&format!("docs-{name}"));
    for entry in REPOSITORY_ENTRIES {
        let path = root().join(entry);
        assert!(path.exists(), "{} is not in the repository", path.display());
        std::os::unix::fs::symlink(&path, dir.join(entry)).unwrap();
    }
    // Scenes are copied, not linked: a scene's paths are relative to its own folder, and
    // `scenes/store/f3.toml` must find the store a command wrote here, not in the clone.
    copy_tree(&root().join("scenes"), &dir.join("scenes"));
    // `target/meshes` (downloaded meshes) where this clone has them.
    std::fs::create_dir_all(dir.join("target")).unwrap();
    let meshes = root().join("target/meshes");
    if meshes.is_dir() {
        let _ = std::os::unix::fs::symlink(meshes, dir.join("target/meshes"));
    }
    dir
}

/// Run arbvis with `args` in `dir` (with `--dry-run` when asked); an error names the line.
fn run_arbvis(dir: &Path, args: &[String], dry_run: bool, at: &str) {
    let mut command = Command::new(env!("CARGO_BIN_EXE_arbvis"));
    command.args(args).current_dir(dir).env("CI", "true");
    if dry_run {
        command.arg("--dry-run");
    }
    let out = command.output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    // A dry run checks every file the scene reads; a scene whose data must be downloaded
    // (its `data_from`) passes when that is all it misses: the error names the file and
    // says how to get it.
    let only_download_missing = dry_run
        && stderr.contains(": no such file: ")
        && stderr.contains("this scene's data is not in the clone: ");
    assert!(
        out.status.success() || only_download_missing,
        "{at}: `arbvis {}`{} failed:\n{}{}",
        args.join(" "),
        if dry_run { " --dry-run" } else { "" },
        String::from_utf8_lossy(&out.stdout),
        stderr
    );
}

/// Subcommands that open a window or take minutes: checked, not run.
const DRY_SUBCOMMANDS: [&str; 3] = ["view", "bench", "study"];

/// What the check did, for the summary line.
#[derive(Default, Debug)]
struct Tally {
    ran: usize,
    dry: usize,
    scripts: usize,
    setup: usize,
}

fn check_line(dir: &Path, line: &Line, tally: &mut Tally) {
    let at = format!("{}:{}", line.file, line.number);
    let mut w = words(&line.text);
    // Leading VAR=value assignments (ARBVIS_FUZZ_SECONDS=600 cargo test ...).
    while w.first().is_some_and(|x| {
        x.contains('=') && x.chars().next().is_some_and(|c| c.is_ascii_uppercase())
    }) {
        w.remove(0);
    }
    let Some(first) = w.first().cloned() else {
        return;
    };
    match first.as_str() {
        "target/release/arbvis" | "arbvis" => {
            let args = w[1..].to_vec();
            let dry = line.dry_run
                || args
                    .first()
                    .is_some_and(|s| DRY_SUBCOMMANDS.contains(&s.as_str()));
            run_arbvis(dir, &args, dry, &at);
            if dry {
                tally.dry += 1;
            } else {
                tally.ran += 1;
            }
        }
        "cargo" => {
            for pair in w.windows(2) {
                if pair[0] == "--test" {
                    let name = &pair[1];
                    assert!(
                        root().join(format!("tests/{name}.rs")).is_file()
                            || root().join(format!("tests/{name}/main.rs")).is_file(),
                        "{at}: `cargo ... --test {name}`: no such test target"
                    );
                }
                if pair[0] == "--example" {
                    let name = &pair[1];
                    assert!(
                        root().join(format!("examples/{name}.rs")).is_file(),
                        "{at}: `cargo ... --example {name}`: no such example"
                    );
                }
            }
            // The main job: what follows `--` is an arbvis command.
            if w.get(1).is_some_and(|s| s == "run") {
                if let Some(split) = w.iter().position(|s| s == "--") {
                    run_arbvis(dir, &w[split + 1..], line.dry_run, &at);
                    tally.ran += 1;
                    return;
                }
            }
            tally.setup += 1;
        }
        "bash" => {
            let script = w.get(1).unwrap_or_else(|| panic!("{at}: bash with no script"));
            assert!(root().join(script).is_file(), "{at}: {script}: no such script");
            tally.setup += 1;
        }
        "pip" => tally.setup += 1,
        "python3" => {
            let script = w.get(1).unwrap_or_else(|| panic!("{at}: python3 with no script"));
            let text = std::fs::read_to_string(root().join(script))
                .unwrap_or_else(|e| panic!("{at}: {script}: {e}"));
            for word in &w[2..] {
                // Flags and sub-commands must be the script's; values and paths are not.
                let is_flag = word.starts_with("--");
                let is_word = word.chars().all(|c| c.is_ascii_lowercase());
                let name = word.split('=').next().unwrap();
                if is_flag || is_word {
                    assert!(
                        text.contains(&format!("\"{name}\"")),
                        "{at}: {script} does not know {name:?}"
                    );
                }
            }
            tally.scripts += 1;
        }
        "head" => {
            let status = Command::new("sh")
                .args(["-c", &line.text])
                .current_dir(dir)
                .status()
                .unwrap();
            assert!(status.success(), "{at}: `{}` failed", line.text);
            tally.ran += 1;
        }
        other => panic!(
            "{at}: `{}`: the docs check does not know how to check {other:?} (teach tests/it/docs.rs)",
            line.text
        ),
    }
}

#[test]
fn every_command_in_the_readme_and_the_guide_works() {
    let mut tally = Tally::default();
    for path in documents() {
        let name = path.strip_prefix(root()).unwrap().display().to_string();
        let text = std::fs::read_to_string(&path).unwrap();
        let lines = sh_commands(&name, &text);
        if lines.is_empty() {
            continue;
        }
        let dir = workdir(&name.replace('/', "-"));
        for line in &lines {
            check_line(&dir, line, &mut tally);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    eprintln!("docs check: {tally:?}");
    // The README's tour alone runs more than ten commands.
    assert!(tally.ran >= 10, "{tally:?}");
}

/// Inline `arbvis ...` spans in prose, with arguments and no placeholder: checked dry.
#[test]
fn inline_commands_in_prose_parse() {
    let dir = workdir("inline");
    let mut checked = 0;
    for path in documents() {
        let name = path.strip_prefix(root()).unwrap().display().to_string();
        let text = std::fs::read_to_string(&path).unwrap();
        for (n, span) in inline_spans(&text) {
            let Some(rest) = span
                .strip_prefix("target/release/arbvis ")
                .or_else(|| span.strip_prefix("arbvis "))
            else {
                continue;
            };
            let literal = !rest.contains("...")
                && !rest.contains('|')
                && !rest.contains('[')
                && !words(rest).iter().any(|w| {
                    // A placeholder: SCENE, RUN.json, COMMAND.
                    let mut c = w.chars();
                    c.next().is_some_and(|c| c.is_ascii_uppercase())
                        && c.next().is_some_and(|c| c.is_ascii_uppercase())
                })
                && words(rest).len() >= 2;
            if literal {
                run_arbvis(&dir, &words(rest), true, &format!("{name}:{n}"));
                checked += 1;
            }
        }
    }
    eprintln!("docs check: {checked} inline commands parsed");
    assert!(checked >= 5, "{checked}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Inline code spans outside fenced blocks, joined across line breaks, with their line.
fn inline_spans(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut fenced = false;
    let mut prose = String::new();
    let mut starts = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if !fenced {
            starts.push((prose.len(), i + 1));
            prose.push_str(line);
            prose.push(' ');
        }
    }
    let line_of = |offset: usize| {
        starts
            .iter()
            .rev()
            .find(|(o, _)| *o <= offset)
            .map_or(1, |&(_, n)| n)
    };
    let mut rest = prose.as_str();
    let mut offset = 0;
    while let Some(open) = rest.find('`') {
        let after = &rest[open + 1..];
        let Some(close) = after.find('`') else {
            break;
        };
        let span = after[..close]
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        out.push((line_of(offset + open), span));
        let consumed = open + 1 + close + 1;
        offset += consumed;
        rest = &rest[consumed..];
    }
    out
}

#[test]
fn the_command_reader_joins_continuations_and_drops_comments() {
    let text = "intro `arbvis x`\n```sh\ncargo build --release && target/release/arbvis info   # the driver\n\
                python3 benches/a.py \\\n    --flag 1\n```\n```toml\nnot = \"a command\"\n```\n";
    let lines = sh_commands("t.md", text);
    let got: Vec<(usize, &str)> = lines.iter().map(|l| (l.number, l.text.as_str())).collect();
    assert_eq!(
        got,
        [
            (3, "cargo build --release"),
            (3, "target/release/arbvis info"),
            (4, "python3 benches/a.py --flag 1")
        ]
    );
    assert_eq!(words("a \"b c\" 'd'"), ["a", "b c", "d"]);
    assert_eq!(strip_comment("x \"#y\" # z"), "x \"#y\" ");
}
