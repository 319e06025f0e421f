//! The README as a user reads it: its example commands run as written, its option tables
//! match the command line's definition (names and defaults), and every documentation link
//! leads to a file.

mod common;

use clap::CommandFactory;
use common::test_device;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn readme() -> String {
    std::fs::read_to_string(repo().join("README.md")).expect("README.md is readable")
}

/// The `penumbra …` commands of the README's `sh` blocks, continuation lines joined.
fn example_commands(text: &str) -> Vec<String> {
    let mut commands = Vec::new();
    let mut in_sh = false;
    let mut pending = String::new();
    for line in text.lines() {
        let trimmed = line.trim();
        if trimmed.starts_with("```") {
            in_sh = !in_sh && trimmed == "```sh";
            continue;
        }
        if !in_sh {
            continue;
        }
        pending.push_str(trimmed.trim_end_matches('\\').trim_end());
        if trimmed.ends_with('\\') {
            pending.push(' ');
            continue;
        }
        let command = std::mem::take(&mut pending);
        if command == "penumbra" || command.starts_with("penumbra ") {
            commands.push(command);
        }
    }
    commands
}

/// Whether a `penumbra` command line opens the viewer (no command, `view`, or a scene).
fn opens_the_viewer(command: &str) -> bool {
    let first = command.split_whitespace().nth(1).unwrap_or("view");
    !matches!(
        first,
        "render" | "devices" | "bench" | "merge" | "help" | "--help" | "-h" | "--version" | "-V"
    )
}

/// Runs every `penumbra` command of the README's `sh` blocks with the built binary first on
/// the PATH, in a fresh folder that holds the repository's `assets/` (the README's commands
/// run from the repository's folder): each ends with exit code 0 and writes what `-o` names.
#[test]
fn the_readme_examples_run_as_written() {
    let commands = example_commands(&readme());
    let headless: Vec<&String> = commands.iter().filter(|c| !opens_the_viewer(c)).collect();
    assert!(
        headless.iter().any(|c| c.starts_with("penumbra render")),
        "the README shows a render: {commands:?}"
    );
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink(repo().join("assets"), dir.path().join("assets")).unwrap();
    let binary = PathBuf::from(env!("CARGO_BIN_EXE_penumbra"));
    let path = format!(
        "{}:{}",
        binary.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    for command in headless {
        let o = Command::new("sh")
            .args(["-c", command])
            .current_dir(dir.path())
            .env("PATH", &path)
            .env("PENUMBRA_DEVICE", test_device())
            .output()
            .expect("sh runs");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "`{command}` failed: {err}");
        let words: Vec<&str> = command.split_whitespace().collect();
        if let Some(i) = words.iter().position(|w| *w == "-o" || *w == "--output") {
            let out = dir.path().join(words[i + 1]);
            let size = std::fs::metadata(&out).map(|m| m.len()).unwrap_or(0);
            assert!(size > 0, "`{command}` wrote nothing to {}", out.display());
            let wrote = format!("penumbra: wrote {}: ", words[i + 1]);
            assert!(err.contains(&wrote), "`{command}`: {err}");
        }
    }
}

/// One row of an option table: the option's long name and its default, as the README says.
struct Row {
    long: String,
    default: String,
}

/// The rows of every README table headed `| option | default | meaning |`.
fn option_rows(text: &str) -> Vec<Row> {
    let mut rows = Vec::new();
    let mut in_table = false;
    for line in text.lines() {
        let cells = table_cells(line);
        if cells.is_empty() {
            in_table = false;
            continue;
        }
        if cells.len() >= 3 && cells[0] == "option" && cells[1] == "default" {
            in_table = true;
            continue;
        }
        if !in_table || cells[0].starts_with("---") {
            continue;
        }
        let long = cells[0]
            .split(|c: char| c.is_whitespace() || c == ',')
            .find(|w| w.starts_with("--"))
            .unwrap_or_else(|| panic!("no --option in the row: {line}"));
        rows.push(Row {
            long: long.to_string(),
            default: cells[1].clone(),
        });
    }
    rows
}

/// The cells of a Markdown table row without code marks; empty for any other line.
fn table_cells(line: &str) -> Vec<String> {
    let line = line.trim();
    if !line.starts_with('|') {
        return Vec::new();
    }
    let mut cells = vec![String::new()];
    let mut chars = line[1..].trim_end_matches('|').chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&'|') => {
                chars.next();
                cells.last_mut().unwrap().push('|');
            }
            '|' => cells.push(String::new()),
            '`' => {}
            c => cells.last_mut().unwrap().push(c),
        }
    }
    cells.into_iter().map(|c| c.trim().to_string()).collect()
}

/// The options of `render` and the viewer by long name: their help (code marks removed), clap's
/// default (if any) and whether they are required.
fn clap_options() -> BTreeMap<String, (String, Option<String>, bool)> {
    let cli = penumbra::cli::Cli::command();
    let mut options = BTreeMap::new();
    for name in ["render", "view"] {
        let command = cli.find_subcommand(name).expect("the command exists");
        for arg in command.get_arguments() {
            let Some(long) = arg.get_long() else {
                continue;
            };
            if matches!(long, "help" | "version") {
                continue;
            }
            let help = arg.get_help().map(|h| h.to_string()).unwrap_or_default();
            let takes_value = arg.get_action().takes_values();
            let default = arg.get_default_values().first().filter(|_| takes_value);
            options.insert(
                format!("--{long}"),
                (
                    help.replace('`', ""),
                    default.map(|d| d.to_string_lossy().into_owned()),
                    arg.is_required_set(),
                ),
            );
        }
    }
    options
}

/// Whether `help` states `default: {default}` (followed by punctuation or its end).
fn states_default(help: &str, default: &str) -> bool {
    let needle = format!("default: {default}");
    help.match_indices(&needle).any(|(i, _)| {
        help[i + needle.len()..]
            .chars()
            .next()
            .is_none_or(|c| matches!(c, ')' | ',' | ';' | '.'))
    })
}

/// Every option of `render` and `view` has one README row whose default is clap's default or
/// the one its help states; every row names an option that exists. A new option needs a row
/// and a help that states its default, nothing here.
#[test]
fn the_readme_option_tables_match_the_help() {
    let rows = option_rows(&readme());
    let options = clap_options();
    assert!(
        rows.len() >= 20,
        "the option tables were found: {}",
        rows.len()
    );
    let mut problems = Vec::new();
    let mut seen = BTreeMap::new();
    for row in &rows {
        if seen.insert(row.long.clone(), ()).is_some() {
            problems.push(format!("{}: two rows", row.long));
        }
        let Some((help, clap_default, required)) = options.get(&row.long) else {
            problems.push(format!(
                "{}: in the README, not in render or view",
                row.long
            ));
            continue;
        };
        let agrees = if *required {
            row.default == "required"
        } else {
            clap_default.as_deref() == Some(row.default.as_str())
                || states_default(help, &row.default)
        };
        if !agrees {
            problems.push(format!(
                "{}: README default '{}', help '{help}' (clap default {clap_default:?})",
                row.long, row.default
            ));
        }
    }
    for (long, (help, clap_default, required)) in &options {
        if !seen.contains_key(long) {
            problems.push(format!("{long}: no row in the README's option tables"));
        }
        if !required && clap_default.is_none() && !help.contains("default: ") {
            problems.push(format!("{long}: the help states no default: '{help}'"));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Markdown link targets (`](target)`) that are not web addresses or anchors.
fn markdown_links(text: &str) -> Vec<String> {
    text.match_indices("](")
        .filter_map(|(i, _)| {
            let rest = &text[i + 2..];
            let target = &rest[..rest.find(')')?];
            let target = target.split('#').next().unwrap_or("");
            let web = target.contains("://") || target.starts_with("mailto:");
            (!web && !target.is_empty()).then(|| target.to_string())
        })
        .collect()
}

/// `docs/…` paths named in text (source comments, help strings).
fn docs_mentions(text: &str) -> Vec<String> {
    text.match_indices("docs/")
        .filter(|(i, _)| {
            let before = text[..*i].chars().next_back();
            before.is_none_or(|c| !c.is_alphanumeric() && c != '_' && c != '/' && c != '.')
        })
        .map(|(i, _)| {
            let rest = &text[i..];
            let end = rest
                .find(|c: char| !(c.is_alphanumeric() || "_-./".contains(c)))
                .unwrap_or(rest.len());
            rest[..end].trim_end_matches('.').to_string()
        })
        .collect()
}

fn files_under(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        if path.is_dir() {
            files_under(&path, ext, out);
        } else if path.extension().is_some_and(|e| e == ext) {
            out.push(path);
        }
    }
}

/// Every link in the README and docs/, and every `docs/…` path the source names, leads to a
/// file or folder of the repository.
#[test]
fn every_documentation_link_leads_to_a_file() {
    let mut pages = vec![repo().join("README.md"), repo().join("scripts/README.md")];
    files_under(&repo().join("docs"), "md", &mut pages);
    let mut sources = Vec::new();
    files_under(&repo().join("src"), "rs", &mut sources);
    let mut broken = Vec::new();
    for page in &pages {
        let text = std::fs::read_to_string(page).unwrap();
        let dir = page.parent().unwrap();
        for target in markdown_links(&text) {
            if !dir.join(&target).exists() {
                broken.push(format!("{}: {target}", page.display()));
            }
        }
    }
    for file in pages.iter().chain(&sources) {
        let text = std::fs::read_to_string(file).unwrap();
        for target in docs_mentions(&text) {
            if !repo().join(&target).exists() {
                broken.push(format!("{}: {target}", file.display()));
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn the_parsers_read_what_the_readme_writes() {
    let text =
        "```sh\npenumbra render a.glb \\\n  -o x.png\ncargo test\n```\n```text\npenumbra x\n```\n";
    assert_eq!(example_commands(text), ["penumbra render a.glb -o x.png"]);
    assert!(opens_the_viewer("penumbra"));
    assert!(opens_the_viewer("penumbra view a.glb"));
    assert!(opens_the_viewer("penumbra a.glb"));
    assert!(!opens_the_viewer("penumbra render a.glb -o x.png"));
    let table = "| option | default | meaning |\n|---|---|---|\n| `-o`, `--output A\\|B` | required | x |\n\n| `--x` | 1 | y |\n";
    let rows = option_rows(table);
    assert_eq!(rows.len(), 1);
    assert_eq!(
        (rows[0].long.as_str(), rows[0].default.as_str()),
        ("--output", "required")
    );
    assert!(states_default(
        "size (default: 640 for render).",
        "640 for render"
    ));
    assert!(!states_default("size (default: 6400).", "640"));
    assert_eq!(
        markdown_links("[a](docs/a.md#x) [b](https://x.org)"),
        ["docs/a.md"]
    );
    assert_eq!(
        docs_mentions("see docs/viewer.md. and mydocs/x"),
        ["docs/viewer.md"]
    );
}
