//! The blocks of a markdown file: text between a start and an end marker, HTML comments that
//! markdown does not show.
//!
//! - A generated block, `<!-- hsp docs: NAME ARGS -->` … `<!-- /hsp docs: NAME -->`: its text is
//!   what the generator `NAME` prints for `ARGS` (see [`super::generators`]).
//! - A timing block, `<!-- hsp timing: LABEL -->` … `<!-- /hsp timing: LABEL -->`: figures that
//!   depend on the machine and cannot be checked against a re-run; its first line must say what
//!   made them (see [`timing_header_problem`]).
//!
//! A block is either inline (both markers on one line, the text between them on that line) or a
//! line block (the start marker ends its line, the end marker begins a line, the text is the
//! lines between them). Markers inside fenced code and inside inline code (right after a
//! backtick) are text, not markers, so that a page can show them.

/// What a block holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Written by a generator.
    Generated,
    /// Timing figures, with a header line saying what made them.
    Timing,
}

impl Kind {
    fn keyword(self) -> &'static str {
        match self {
            Kind::Generated => "hsp docs:",
            Kind::Timing => "hsp timing:",
        }
    }
}

/// One block of a file.
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    pub kind: Kind,
    /// The generator's name (or the timing block's label).
    pub name: String,
    /// The generator's arguments, split as a shell would (single quotes group).
    pub args: Vec<String>,
    /// The start marker's line, from 1.
    pub line: usize,
    /// Both markers on one line.
    pub inline: bool,
    /// The block's text: `text[start..end]` of the file.
    pub start: usize,
    pub end: usize,
}

impl Block {
    /// The name and arguments as written in the start marker.
    pub fn key(&self) -> String {
        std::iter::once(self.name.as_str())
            .chain(self.args.iter().map(String::as_str))
            .collect::<Vec<_>>()
            .join(" ")
    }
}

/// A marker found in a line.
struct Marker {
    kind: Kind,
    end_marker: bool,
    /// Byte offsets of `<!--` and just after `-->`.
    at: usize,
    after: usize,
    words: Vec<String>,
}

/// Splits a marker's words as a shell would: whitespace separates, single quotes group.
fn split_words(s: &str) -> Result<Vec<String>, String> {
    let mut words = Vec::new();
    let mut word = String::new();
    let mut quoted = false;
    let mut any = false;
    for c in s.chars() {
        match c {
            '\'' => {
                quoted = !quoted;
                any = true;
            }
            c if c.is_whitespace() && !quoted => {
                if any {
                    words.push(std::mem::take(&mut word));
                    any = false;
                }
            }
            c => {
                word.push(c);
                any = true;
            }
        }
    }
    if quoted {
        return Err(format!("unbalanced single quote in '{s}'"));
    }
    if any {
        words.push(word);
    }
    Ok(words)
}

/// The markers in one line starting at byte `offset` of the file.
fn markers(line: &str, offset: usize) -> Result<Vec<Marker>, String> {
    let mut found = Vec::new();
    let mut from = 0;
    while let Some(i) = line[from..].find("<!--") {
        let at = from + i;
        from = at + 4;
        if line[..at].ends_with('`') {
            continue;
        }
        let rest = line[at + 4..].trim_start();
        let (end_marker, rest) = match rest.strip_prefix('/') {
            Some(r) => (true, r),
            None => (false, rest),
        };
        let Some(kind) = [Kind::Generated, Kind::Timing]
            .into_iter()
            .find(|k| rest.starts_with(k.keyword()))
        else {
            continue;
        };
        let body = &rest[kind.keyword().len()..];
        let close = body
            .find("-->")
            .ok_or_else(|| format!("a marker '<!-- {}' without its '-->'", kind.keyword()))?;
        let words = split_words(&body[..close])?;
        if words.is_empty() {
            return Err(format!("a marker '<!-- {}' without a name", kind.keyword()));
        }
        let after = line.len() - body.len() + close + 3;
        from = after;
        found.push(Marker {
            kind,
            end_marker,
            at: offset + at,
            after: offset + after,
            words,
        });
    }
    Ok(found)
}

/// The blocks of a file's text, or the problems of its markers (each with its line): an end
/// marker without its start, a start without its end, a block inside another, markers neither
/// on one line nor ending and beginning lines.
pub fn parse(text: &str) -> Result<Vec<Block>, Vec<String>> {
    let mut blocks = Vec::new();
    let mut problems = Vec::new();
    let mut open: Option<(Marker, usize)> = None;
    let mut fence: Option<String> = None;
    let mut offset = 0;
    for (i, line) in text.split_inclusive('\n').enumerate() {
        let number = i + 1;
        let line_start = offset;
        offset += line.len();
        let trimmed = line.trim_start();
        if open.is_none() {
            if let Some(f) = &fence {
                if trimmed.starts_with(f.as_str()) {
                    fence = None;
                }
                continue;
            }
            if trimmed.starts_with("```") || trimmed.starts_with("~~~") {
                fence = Some(trimmed[..3].to_string());
                continue;
            }
        }
        let found = match markers(line, line_start) {
            Ok(f) => f,
            Err(e) => {
                problems.push(format!("line {number}: {e}"));
                continue;
            }
        };
        for m in found {
            match (open.take(), m.end_marker) {
                (None, false) => open = Some((m, number)),
                (None, true) => problems.push(format!(
                    "line {number}: end marker '<!-- /{} {} -->' without its start",
                    m.kind.keyword(),
                    m.words[0]
                )),
                (Some((s, l)), false) => {
                    problems.push(format!(
                        "line {l}: block '{}' has no end marker '<!-- /{} {} -->' before the \
                         next block at line {number}",
                        s.words[0],
                        s.kind.keyword(),
                        s.words[0]
                    ));
                    open = Some((m, number));
                }
                (Some((s, l)), true) => {
                    if s.kind != m.kind || s.words[0] != m.words[0] {
                        problems.push(format!(
                            "line {number}: end marker '{} {}' does not close block '{} {}' of \
                             line {l}",
                            m.kind.keyword(),
                            m.words[0],
                            s.kind.keyword(),
                            s.words[0]
                        ));
                        continue;
                    }
                    let inline = l == number;
                    let starts_line =
                        text[s.after..].starts_with('\n') || text[s.after..].starts_with("\r\n");
                    let begins_line = text[line_start..m.at].trim().is_empty();
                    let start = if inline {
                        s.after
                    } else if starts_line && begins_line {
                        s.after + text[s.after..].find('\n').map_or(0, |n| n + 1)
                    } else {
                        problems.push(format!(
                            "line {l}: block '{}': put both markers on one line, or the start \
                             marker at the end of its line and the end marker at the start of \
                             line {number}",
                            s.words[0]
                        ));
                        continue;
                    };
                    blocks.push(Block {
                        kind: s.kind,
                        name: s.words[0].clone(),
                        args: s.words[1..].to_vec(),
                        line: l,
                        inline,
                        start,
                        end: if inline { m.at } else { line_start },
                    });
                }
            }
        }
    }
    if let Some((s, l)) = open {
        problems.push(format!(
            "line {l}: block '{}' has no end marker '<!-- /{} {} -->'",
            s.words[0],
            s.kind.keyword(),
            s.words[0]
        ));
    }
    if problems.is_empty() {
        Ok(blocks)
    } else {
        Err(problems)
    }
}

/// Why a timing block's first line is not the header it needs, `None` if it is. The header:
///
/// ```text
/// Made by `COMMAND` on YYYY-MM-DD, load L.
/// ```
///
/// (more text may follow on the line; `load` may say `not recorded`).
pub fn timing_header_problem(content: &str) -> Option<String> {
    let first = content.lines().find(|l| !l.trim().is_empty()).unwrap_or("");
    let want = "its first line must be 'Made by `COMMAND` on YYYY-MM-DD, load L.'";
    let Some(rest) = first.trim().strip_prefix("Made by `") else {
        return Some(format!("{want}; it is '{first}'"));
    };
    let Some(close) = rest.find('`').filter(|&c| c > 0) else {
        return Some(format!("{want}: no command in backticks"));
    };
    let Some(date) = rest[close + 1..].strip_prefix(" on ") else {
        return Some(format!("{want}: no ' on ' after the command"));
    };
    let d = date.as_bytes();
    let is_date = d.len() >= 10
        && d[..10].iter().enumerate().all(|(i, c)| {
            if i == 4 || i == 7 {
                *c == b'-'
            } else {
                c.is_ascii_digit()
            }
        });
    if !is_date {
        return Some(format!("{want}: no date YYYY-MM-DD after 'on'"));
    }
    match date.find(", load ") {
        Some(i) if date[i + 7..].trim().len() > 1 => None,
        _ => Some(format!("{want}: no ', load L' after the date")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_and_inline_blocks_with_their_texts() {
        let text = "a\n<!-- hsp docs: one x 'y z' -->\nold\n<!-- /hsp docs: one -->\n\
                    b <!-- hsp docs: two -->1.5<!-- /hsp docs: two --> c\n";
        let blocks = parse(text).unwrap();
        assert_eq!(blocks.len(), 2);
        assert_eq!(blocks[0].args, ["x", "y z"]);
        assert_eq!(&text[blocks[0].start..blocks[0].end], "old\n");
        assert!(!blocks[0].inline && blocks[1].inline);
        assert_eq!(&text[blocks[1].start..blocks[1].end], "1.5");
        assert_eq!(blocks[1].line, 5);
    }

    #[test]
    fn markers_in_code_are_text() {
        let text = "```\n<!-- hsp docs: one -->\n```\nsee `<!-- hsp docs: NAME -->`\n";
        assert_eq!(parse(text).unwrap(), vec![]);
    }

    #[test]
    fn a_missing_or_foreign_end_marker_is_named() {
        let e = parse("<!-- hsp docs: one -->\nx\n").unwrap_err();
        assert!(
            e[0].contains("line 1") && e[0].contains("'one' has no end marker"),
            "{e:?}"
        );
        let e = parse("<!-- hsp docs: one -->\nx\n<!-- /hsp docs: two -->\n").unwrap_err();
        assert!(e[0].contains("does not close block"), "{e:?}");
        let e = parse("x <!-- /hsp timing: t -->\n").unwrap_err();
        assert!(e[0].contains("without its start"), "{e:?}");
    }

    #[test]
    fn timing_headers() {
        assert_eq!(
            timing_header_problem("\nMade by `bench-fmu` on 2026-12-05, load 4 to 6.\n|a|\n"),
            None
        );
        assert_eq!(
            timing_header_problem("Made by `x` on 2026-12-05, load not recorded; more.\n"),
            None
        );
        assert!(timing_header_problem("| a | b |\n").is_some());
        assert!(timing_header_problem("Made by `x` on 5 Dec, load 4.\n").is_some());
        assert!(timing_header_problem("Made by `x` on 2026-12-05.\n").is_some());
    }
}
