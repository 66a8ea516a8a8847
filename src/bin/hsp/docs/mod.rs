//! `hsp docs [--check] [--root DIR]`: the figures of the documentation that do not depend on the
//! machine's speed, written by the tools that compute them.
//!
//! A markdown file marks such a figure as a generated block (see [`blocks`]):
//!
//! ```text
//! <!-- hsp docs: NAME ARGS -->
//! ...
//! <!-- /hsp docs: NAME -->
//! ```
//!
//! or inline, `<!-- hsp docs: NAME ARGS -->4.914<!-- /hsp docs: NAME -->`. `NAME` is one of
//! [`generators::GENERATORS`], which computes the text in-process from `ARGS` with the functions
//! the other subcommands call. `hsp docs` rewrites every block in place; `hsp docs --check` writes
//! nothing and fails, naming the file, the line and the block with a short diff, when a block's
//! text differs from what its generator gives now, when a block names no generator, when a
//! marker has no end, and when a timing block (`<!-- hsp timing: LABEL -->`, machine-dependent
//! figures that no re-run can check) does not begin with the line saying what made it: `Made by
//! `COMMAND` on YYYY-MM-DD, load L.` A generator that cannot run here (no packaged FMU, or one
//! without the portable binaries whose sizes a block quotes) skips its block with a message.
//!
//! The files: `README.md`, `CONTRIBUTING.md`, `docs/*.md` and `bench/*.md` under the root.

mod blocks;
mod generators;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use blocks::{Block, Kind};
use generators::{Context, Output, GENERATORS};

/// The files `hsp docs` reads, under the root: these and every `.md` of [`DIRS`].
const FILES: &[&str] = &["README.md", "CONTRIBUTING.md"];
const DIRS: &[&str] = &["docs", "bench"];

/// The markdown files under `root` that `hsp docs` reads, in order.
fn files(root: &Path) -> Result<Vec<PathBuf>, String> {
    let mut all: Vec<PathBuf> = FILES
        .iter()
        .map(|f| root.join(f))
        .filter(|p| p.exists())
        .collect();
    for dir in DIRS {
        let Ok(entries) = std::fs::read_dir(root.join(dir)) else {
            continue;
        };
        let mut md: Vec<PathBuf> = entries
            .map(|e| e.map(|e| e.path()))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| format!("{}: {e}", root.join(dir).display()))?
            .into_iter()
            .filter(|p| p.extension().is_some_and(|x| x == "md"))
            .collect();
        md.sort();
        all.extend(md);
    }
    if all.is_empty() {
        return Err(format!(
            "{} has no README.md, CONTRIBUTING.md, docs/*.md or bench/*.md",
            root.display()
        ));
    }
    Ok(all)
}

/// The text a generated block should hold, or why it is skipped.
fn wanted(
    ctx: &Context,
    block: &Block,
    cache: &mut HashMap<String, Result<Output, String>>,
) -> Result<Output, String> {
    let entry = cache.entry(block.key()).or_insert_with(|| {
        let (_, _, generate) = GENERATORS
            .iter()
            .find(|(name, _, _)| *name == block.name)
            .ok_or_else(|| {
                format!(
                    "unknown block '{}' (known: {})",
                    block.name,
                    GENERATORS
                        .iter()
                        .map(|g| g.0)
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })?;
        generate(ctx, &block.args)
    });
    let out = entry.clone()?;
    Ok(match out {
        Output::Text(t) if block.inline && t.contains('\n') => {
            return Err(format!(
                "block '{}' is inline but its text has several lines: make it a line block",
                block.key()
            ))
        }
        Output::Text(t) if !block.inline && !t.is_empty() => {
            Output::Text(format!("{}\n", t.trim_end_matches('\n')))
        }
        other => other,
    })
}

/// A short diff of a block's text: the lines between the common first and last lines.
fn diff(have: &str, want: &str) -> String {
    let h: Vec<&str> = have.lines().collect();
    let w: Vec<&str> = want.lines().collect();
    let head = h.iter().zip(&w).take_while(|(a, b)| a == b).count();
    let tail = h[head..]
        .iter()
        .rev()
        .zip(w[head..].iter().rev())
        .take_while(|(a, b)| a == b)
        .count();
    let mut s = String::new();
    let show = |sign: char, lines: &[&str], s: &mut String| {
        for l in lines.iter().take(8) {
            s.push_str(&format!(
                "    {sign} {}\n",
                l.chars().take(200).collect::<String>()
            ));
        }
        if lines.len() > 8 {
            s.push_str(&format!("    {sign} ({} more lines)\n", lines.len() - 8));
        }
    };
    show('-', &h[head..h.len() - tail], &mut s);
    show('+', &w[head..w.len() - tail], &mut s);
    s
}

/// What `hsp docs` found: the problems (each naming its file: an unknown block, a marker
/// without its end, a timing block without its header, a generator's error), the blocks whose
/// text differs, the skipped blocks' messages, the number of blocks and the files whose new text
/// differs.
struct Pass {
    problems: Vec<String>,
    stale: Vec<String>,
    skipped: Vec<String>,
    blocks: usize,
    rewritten: Vec<(PathBuf, String)>,
}

fn pass(root: &Path, check: bool) -> Result<Pass, String> {
    let ctx = Context {
        root: root.to_path_buf(),
        check,
    };
    let mut cache = HashMap::new();
    let mut p = Pass {
        problems: Vec::new(),
        stale: Vec::new(),
        skipped: Vec::new(),
        blocks: 0,
        rewritten: Vec::new(),
    };
    for path in files(root)? {
        let shown = path
            .strip_prefix(root)
            .unwrap_or(&path)
            .display()
            .to_string();
        let text =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let blocks = match blocks::parse(&text) {
            Ok(b) => b,
            Err(problems) => {
                p.problems
                    .extend(problems.into_iter().map(|e| format!("{shown}: {e}")));
                continue;
            }
        };
        let mut new = String::new();
        let mut at = 0;
        for b in &blocks {
            p.blocks += 1;
            let have = &text[b.start..b.end];
            let at_block = format!("{shown}:{}: block '{}'", b.line, b.key());
            let want = match b.kind {
                Kind::Timing => {
                    if let Some(e) = blocks::timing_header_problem(have) {
                        p.problems.push(format!(
                            "{shown}:{}: timing block '{}': {e}",
                            b.line, b.name
                        ));
                    }
                    continue;
                }
                Kind::Generated => match wanted(&ctx, b, &mut cache) {
                    Ok(Output::Text(t)) => t,
                    Ok(Output::Skip(why)) => {
                        p.skipped.push(format!("{at_block} not checked: {why}"));
                        continue;
                    }
                    Err(e) => {
                        p.problems.push(format!("{at_block}: {e}"));
                        continue;
                    }
                },
            };
            if have != want {
                p.stale.push(format!(
                    "{at_block} differs from what `hsp docs` writes:\n{}",
                    diff(have, &want).trim_end()
                ));
                new.push_str(&text[at..b.start]);
                new.push_str(&want);
                at = b.end;
            }
        }
        if at > 0 {
            new.push_str(&text[at..]);
            p.rewritten.push((path, new));
        }
    }
    Ok(p)
}

/// `hsp docs [--check]` under `root`: rewrites (or, with `check`, compares) every generated
/// block and checks every timing block's header. Returns the lines to print: the files written
/// or the count checked, and the skipped blocks; with `list`, only the generators.
pub fn run(root: &Path, check: bool, list: bool) -> Result<Vec<String>, String> {
    if list {
        return Ok(GENERATORS
            .iter()
            .map(|(name, what, _)| format!("{name:<18} {what}"))
            .collect());
    }
    let p = pass(root, check)?;
    let mut said: Vec<String> = p.skipped.iter().map(|s| format!("skipped {s}")).collect();
    if check {
        if !p.problems.is_empty() || !p.stale.is_empty() {
            let mut all = p.problems;
            all.extend(p.stale);
            all.extend(said);
            all.push("run `cargo run --release --bin hsp -- docs` and commit the result".into());
            return Err(all.join("\n"));
        }
        said.push(format!(
            "checked {} blocks under {}",
            p.blocks,
            root.display()
        ));
        return Ok(said);
    }
    // Only the stale blocks are rewritten; any other problem stops the run before any write.
    if !p.problems.is_empty() {
        return Err(p.problems.join("\n"));
    }
    for (path, text) in &p.rewritten {
        std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))?;
        said.push(format!("wrote {}", path.display()));
    }
    said.push(format!(
        "{} blocks, {} files rewritten",
        p.blocks,
        p.rewritten.len()
    ));
    Ok(said)
}
