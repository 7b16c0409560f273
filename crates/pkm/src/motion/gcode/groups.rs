//! What a controller refuses on one line, before any of it is applied: two codes of
//! one modal group (`G1 G0`, `G21 G20`, `M3 M5`), a word given twice (`X1 X2`,
//! `F60 F6000`). The `gcode` crate reads such a line and the last word would win; a
//! controller stops there. The groups are LinuxCNC's (rs274ngc's `_gees` and `_ems`
//! tables, the G-code overview's "modal groups"), for the codes pkm accepts; its
//! messages ("Two G codes used from same modal group", "Multiple X words on one
//! line") are the model of these.

use super::err_at;
use crate::error::Result;

/// A modal group: its letter, LinuxCNC's number and name, and the codes of it that
/// pkm accepts (major number, decimal).
struct Group {
    letter: char,
    number: u8,
    name: &'static str,
    codes: &'static [(u32, Option<u32>)],
}

/// The modal groups of the codes pkm accepts; a code of no group here (an M code of a
/// controller's own) takes part in no check.
const GROUPS: &[Group] = &[
    Group {
        letter: 'G',
        number: 0,
        name: "non-modal",
        codes: &[(4, None), (53, None)],
    },
    Group {
        letter: 'G',
        number: 1,
        name: "motion",
        codes: &[(0, None), (1, None), (2, None), (3, None)],
    },
    Group {
        letter: 'G',
        number: 2,
        name: "plane selection",
        codes: &[(17, None), (18, None), (19, None)],
    },
    Group {
        letter: 'G',
        number: 3,
        name: "distance mode",
        codes: &[(90, None), (91, None)],
    },
    Group {
        letter: 'G',
        number: 4,
        name: "arc IJK distance mode",
        codes: &[(90, Some(1)), (91, Some(1))],
    },
    Group {
        letter: 'G',
        number: 5,
        name: "feed rate mode",
        codes: &[(93, None), (94, None)],
    },
    Group {
        letter: 'G',
        number: 6,
        name: "units",
        codes: &[(20, None), (21, None)],
    },
    Group {
        letter: 'G',
        number: 7,
        name: "cutter radius compensation",
        codes: &[(40, None)],
    },
    Group {
        letter: 'G',
        number: 8,
        name: "tool length offset",
        codes: &[(43, None), (49, None)],
    },
    Group {
        letter: 'G',
        number: 12,
        name: "coordinate system",
        codes: &[
            (54, None),
            (55, None),
            (56, None),
            (57, None),
            (58, None),
            (59, None),
            (59, Some(1)),
            (59, Some(2)),
            (59, Some(3)),
        ],
    },
    Group {
        letter: 'M',
        number: 4,
        name: "stopping",
        codes: &[(0, None), (1, None), (2, None), (30, None)],
    },
    Group {
        letter: 'M',
        number: 6,
        name: "tool change",
        codes: &[(6, None)],
    },
    Group {
        letter: 'M',
        number: 7,
        name: "spindle",
        codes: &[(3, None), (4, None), (5, None)],
    },
    Group {
        letter: 'M',
        number: 8,
        name: "coolant",
        codes: &[(7, None), (8, None), (9, None)],
    },
];

/// The index in [`GROUPS`] of the group of code `letter major.minor`, if it has one.
fn group_of(letter: char, major: u32, minor: Option<u32>) -> Option<usize> {
    GROUPS
        .iter()
        .position(|g| g.letter == letter && g.codes.contains(&(major, minor)))
}

/// Refuses line `line` (its `text`, read to `codes` and `words`) when two of its codes
/// are of one modal group or a word letter comes twice (a T code counts as a word, N
/// is the line number), naming the column of the second.
pub(super) fn check(
    codes: &[(char, u32, Option<u32>)],
    words: &[(char, f64)],
    text: &str,
    line: u64,
) -> Result<()> {
    // One bit per group of `GROUPS`, and one per letter A..Z.
    let mut groups = 0u32;
    let mut letters = 0u32;
    let mut nth = [0usize; 2];
    for &(letter, major, minor) in codes {
        let kind = usize::from(letter == 'M');
        let k = nth[kind];
        if letter != 'T' {
            nth[kind] += 1;
        }
        if let Some(g) = group_of(letter, major, minor) {
            if groups & (1 << g) != 0 {
                return Err(same_group(codes, g, k, text, line));
            }
            groups |= 1 << g;
        }
    }
    let tools = codes.iter().filter(|c| c.0 == 'T').map(|_| 'T');
    for l in words.iter().map(|w| w.0).chain(tools) {
        if l == 'N' || !l.is_ascii_uppercase() {
            continue;
        }
        let bit = 1 << (l as u8 - b'A');
        if letters & bit != 0 {
            let column = column_of(text, l, 1);
            return Err(err_at(
                line,
                column,
                format!("multiple {l} words on one line"),
            ));
        }
        letters |= bit;
    }
    Ok(())
}

/// The error of the `k`-th code of its letter (0-based) in `codes`, of group `g` that
/// an earlier code of the line is in.
fn same_group(
    codes: &[(char, u32, Option<u32>)],
    g: usize,
    k: usize,
    text: &str,
    line: u64,
) -> crate::error::Error {
    let group = &GROUPS[g];
    let name = |&(l, major, minor): &(char, u32, Option<u32>)| match minor {
        Some(m) => format!("{l}{major}.{m}"),
        None => format!("{l}{major}"),
    };
    let mut in_group = codes
        .iter()
        .filter(|c| group_of(c.0, c.1, c.2) == Some(g))
        .map(name);
    let first = in_group.next().unwrap_or_default();
    let second = in_group.next().unwrap_or_default();
    let members: Vec<String> = group
        .codes
        .iter()
        .map(|&(major, minor)| name(&(group.letter, major, minor)))
        .collect();
    err_at(
        line,
        column_of(text, group.letter, k),
        format!(
            "{first} and {second}: two {} codes used from the same modal group (group {}, {}: {})",
            group.letter,
            group.number,
            group.name,
            members.join(" ")
        ),
    )
}

/// The 1-based column (in characters) of the `k`-th (0-based) word of `letter` in
/// `text`, outside comments; the line's end when there is none (a word the crate
/// found in a form this scan does not know).
fn column_of(text: &str, letter: char, k: usize) -> usize {
    let mut depth = 0usize;
    let mut seen = 0;
    for (i, c) in text.char_indices() {
        match c {
            ';' if depth == 0 => break,
            '(' => depth += 1,
            ')' => depth = depth.saturating_sub(1),
            c if depth == 0 && c.eq_ignore_ascii_case(&letter) => {
                if seen == k {
                    return text[..i].chars().count() + 1;
                }
                seen += 1;
            }
            _ => {}
        }
    }
    text.chars().count() + 1
}
