//! Prints the GUID of the model description read on standard input, whose `guid` attribute is
//! blank (`guid=""`): the rule of `src/fnv1a.rs`, the one copy that `build.rs` checks with.
//!
//! `modelDescription/update.py` compiles this file with plain `rustc` (no Cargo, no `build.rs`:
//! the crate's build fails while the GUID is stale, which is when the GUID is wanted) and runs it:
//!
//! ```text
//! rustc --edition 2021 -O tools/guid.rs -o /tmp/guid && /tmp/guid < modelDescription.xml
//! ```

#[path = "../src/fnv1a.rs"]
#[allow(dead_code)]
mod fnv1a;

use std::io::Read;
use std::process::ExitCode;

fn main() -> ExitCode {
    let mut text = String::new();
    if let Err(e) = std::io::stdin().read_to_string(&mut text) {
        eprintln!("guid: cannot read standard input: {e}");
        return ExitCode::FAILURE;
    }
    if !text.contains("guid=\"\"") {
        eprintln!("guid: the text on standard input has no blank guid=\"\"");
        return ExitCode::FAILURE;
    }
    println!("{}", fnv1a::model_guid(&text, ""));
    ExitCode::SUCCESS
}
