//! The README's tour and the docs' examples are real: every `$ pkm ...` command a page
//! shows runs, in order, in one directory per page (later commands read what earlier
//! ones wrote), and the lines it prints under a command are that command's output
//! (standard output, then standard error, or the other way round; empty lines
//! aside), in order and none left
//! out: a line `...` stands for any number of lines, a line ending in `...` for one
//! line it begins, and a run time (`in 0.055 s`) may differ.

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

/// Whether `line` of a command's output is the shown line `s`: the same up to a run
/// time, or beginning with what precedes a trailing `...`.
fn line_is(s: &str, line: &str) -> bool {
    match s.strip_suffix("...") {
        Some(prefix) => line.starts_with(prefix.trim_end()),
        None => without_time(s) == line,
    }
}

/// Whether the shown lines `shown` are the output `lines`: each stretch between `...`
/// lines is a stretch of consecutive output lines, in order; the first begins the
/// output unless `...` precedes it, the last ends it unless `...` follows it.
fn shows(shown: &[String], lines: &[String]) -> bool {
    let shown: Vec<&str> = shown
        .iter()
        .map(|s| s.as_str())
        .filter(|s| !s.is_empty())
        .collect();
    let parts: Vec<&[&str]> = shown.split(|s| *s == "...").collect();
    let at = |part: &[&str], k: usize| {
        k + part.len() <= lines.len() && part.iter().zip(&lines[k..]).all(|(s, l)| line_is(s, l))
    };
    let last = parts.len() - 1;
    let mut cursor = 0;
    for (i, part) in parts.iter().enumerate() {
        if part.is_empty() {
            continue;
        }
        if i == last && last > 0 {
            // The last stretch ends the output (anywhere from the cursor on).
            return lines.len() >= cursor + part.len() && at(part, lines.len() - part.len());
        }
        let found = if i == 0 {
            at(part, 0).then_some(0)
        } else {
            (cursor..=lines.len().saturating_sub(part.len())).find(|&k| at(part, k))
        };
        match found {
            Some(k) => cursor = k + part.len(),
            None => return false,
        }
        if i == last {
            // One stretch and no `...`: it is the whole output.
            return cursor == lines.len();
        }
    }
    true
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
        let (stdout, stderr) = (
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr),
        );
        let lines = |text: String| -> Vec<String> {
            text.lines()
                .map(|l| without_time(l.trim()))
                .filter(|l| !l.is_empty())
                .collect()
        };
        // A terminal shows a warning written before the output above it.
        let text = format!("{stdout}{stderr}");
        let shown_ok =
            shows(shown, &lines(text.clone())) || shows(shown, &lines(format!("{stderr}{stdout}")));
        if !shown.is_empty() && !shown_ok {
            wrong.push(format!(
                "{page}: pkm {cmd}\n  shown:\n{}\n  output:\n{text}",
                shown.join("\n")
            ));
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

/// A shown block is the output with `...` for what it leaves out, nothing dropped
/// silently.
#[test]
fn a_shown_block_leaves_lines_out_only_where_it_says_so() {
    let out: Vec<String> = ["name (tripod)", "pose X=1", "actuator e 3", "limits ok"]
        .map(String::from)
        .to_vec();
    let v = |s: &[&str]| s.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    assert!(shows(
        &v(&["name (tripod)", "pose X=1", "actuator e 3", "limits ok"]),
        &out
    ));
    assert!(shows(&v(&["name (tripod)", "...", "limits ok"]), &out));
    assert!(shows(&v(&["...", "actuator e 3", "..."]), &out));
    assert!(shows(&v(&["name (tripod)", "pose X...", "..."]), &out));
    assert!(shows(&v(&["...", "limits ok"]), &out));
    // The header dropped, a line dropped in between, the end dropped: refused.
    assert!(!shows(&v(&["pose X=1", "...", "limits ok"]), &out));
    assert!(!shows(&v(&["name (tripod)", "actuator e 3", "..."]), &out));
    assert!(!shows(&v(&["name (tripod)", "pose X=1"]), &out));
    assert!(!shows(&v(&["...", "actuator e 3"]), &out));
    assert!(!shows(&v(&["...", "limits ok", "pose X=1"]), &out));
}
