//! The README's tour and the docs' examples are real: every `$ pkm ...` command a page
//! shows runs, in order, in one directory per page (later commands read what earlier
//! ones wrote), and every output line it prints under a command is a line of that
//! command's output. A line ending in `...` stands for any line it begins; a run time
//! (`in 0.055 s`) may differ.

use super::common::path;

/// The README's commands, each with the output lines shown under it.
fn tour(readme: &str) -> Vec<(String, Vec<String>)> {
    let mut blocks: Vec<(String, Vec<String>)> = Vec::new();
    let mut open = false;
    for line in readme.lines() {
        if let Some(cmd) = line.strip_prefix("    $ pkm ") {
            blocks.push((cmd.to_string(), Vec::new()));
            open = true;
        } else if let (true, Some(out)) = (open, line.strip_prefix("    ")) {
            if let Some(b) = blocks.last_mut() {
                b.1.push(out.trim().to_string());
            }
        } else {
            open = false;
        }
    }
    blocks
}

/// `line` with the number of a trailing `in N s` replaced by `#`.
fn without_time(line: &str) -> String {
    let words: Vec<&str> = line.split(' ').collect();
    let n = words.len();
    if n >= 3 && words[n - 1] == "s" && words[n - 3] == "in" && words[n - 2].parse::<f64>().is_ok()
    {
        let mut w = words.clone();
        w[n - 2] = "#";
        return w.join(" ");
    }
    line.to_string()
}

/// The commands of `page` (a path from the repository's root) that do not print what
/// the page shows, each with the line and the output.
#[cfg(unix)]
fn mismatches(page: &str) -> Vec<String> {
    let text = std::fs::read_to_string(path(page)).unwrap();
    let blocks = tour(&text);
    let dir = tempfile::tempdir().unwrap();
    // The commands name files by their paths from the repository's root.
    for d in ["examples", "tests"] {
        std::os::unix::fs::symlink(path(d), dir.path().join(d)).unwrap();
    }
    let bin = assert_cmd::cargo::cargo_bin("pkm");
    let mut wrong = Vec::new();
    for (cmd, shown) in &blocks {
        // A trailing comment is the page's, not the shell's.
        let cmd = cmd.split("  #").next().unwrap_or(cmd).trim();
        let out = std::process::Command::new("sh")
            .arg("-c")
            .arg(format!("'{}' {cmd}", bin.display()))
            .current_dir(dir.path())
            .output()
            .unwrap();
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        let lines: Vec<String> = text.lines().map(|l| without_time(l.trim())).collect();
        for s in shown.iter().filter(|s| !s.is_empty() && *s != "...") {
            let found = match s.strip_suffix("...") {
                Some(prefix) => lines.iter().any(|l| l.starts_with(prefix.trim_end())),
                None => lines.contains(&without_time(s)),
            };
            if !found {
                wrong.push(format!(
                    "{page}: pkm {cmd}\n  shown: {s}\n  output:\n{text}"
                ));
            }
        }
    }
    wrong
}

#[cfg(unix)]
#[test]
fn readme_commands_print_what_the_readme_shows() {
    assert!(tour(&std::fs::read_to_string(path("README.md")).unwrap()).len() >= 25);
    let wrong = mismatches("README.md");
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[cfg(unix)]
#[test]
fn docs_commands_print_what_the_docs_show() {
    let mut pages: Vec<String> = std::fs::read_dir(path("docs"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".md"))
        .map(|n| format!("docs/{n}"))
        .collect();
    pages.sort();
    let commands: usize = pages
        .iter()
        .map(|p| tour(&std::fs::read_to_string(path(p)).unwrap()).len())
        .sum();
    assert!(commands >= 4, "{commands} commands in {pages:?}");
    let wrong: Vec<String> = pages.iter().flat_map(|p| mismatches(p)).collect();
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// The parser finds commands and their lines, and the time mask leaves other numbers.
#[test]
fn tour_reads_commands_and_their_lines() {
    let text = "intro\n\n    $ pkm check a.toml\n    name (tripod)\n    ...\n\nprose\n    $ pkm ik a.toml  # note\n";
    let t = tour(text);
    assert_eq!(t.len(), 2);
    assert_eq!(t[0].0, "check a.toml");
    assert_eq!(t[0].1, vec!["name (tripod)", "..."]);
    assert!(t[1].1.is_empty());
    assert_eq!(
        without_time("x: 68921 points in 0.055 s"),
        "x: 68921 points in # s"
    );
    assert_eq!(without_time("peak 0.055 s"), "peak 0.055 s");
}
