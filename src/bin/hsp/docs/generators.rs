//! The generators of `hsp docs`: each block name maps to one function that computes the block's
//! text in-process with the functions the other subcommands call (`hsp modes`, `hsp frf`,
//! `hsp info`, `hsp presets`, `hsp run`, `hsp package`'s archives), from the block's arguments.
//! Arguments are those of the subcommand (`--preset P --set NAME=VALUE ...`) where there is one.

use std::io::Read as _;
use std::path::{Path, PathBuf};

use clap::Parser as _;
use hydraulic_slewing_plate::eigen;
use hydraulic_slewing_plate::model::variables::MODEL_IDENTIFIER;
use hydraulic_slewing_plate::SOURCE_HASH;
use nalgebra::Complex;

use super::super::{fastest, package, run, validate::num, Cli, Command, ModelArgs};
use crate::model_description::ModelDescription;

/// What a generator gives for a block.
#[derive(Clone, Debug, PartialEq)]
pub enum Output {
    /// The block's text (one line for an inline block, lines without the final newline for a
    /// line block).
    Text(String),
    /// The figures cannot be made here (e.g. the FMU lacks a binary): the block is left as it
    /// is and the reason printed.
    Skip(String),
}

/// What the generators read besides the model: the repository root (for the packaged FMUs), and
/// whether this is `--check` (a figure that a rebuild elsewhere would change is written, not
/// checked).
pub struct Context {
    pub root: PathBuf,
    pub check: bool,
}

/// A generator: the context and the block's arguments to its text.
type Generate = fn(&Context, &[String]) -> Result<Output, String>;

/// Every generator: its name, what it writes, the function.
pub const GENERATORS: &[(&str, &str, Generate)] = &[
    (
        "mode-hz",
        "`mode-hz (N,M) [--preset P] [--set ...]`: that mode's frequency from `hsp modes`, Hz, \
         3 decimals",
        mode_hz,
    ),
    (
        "frf-peaks",
        "`frf-peaks [hsp frf arguments]`: the resonance peaks `hsp frf` finds, Hz, 3 decimals",
        frf_peaks,
    ),
    (
        "info",
        "`info FIELD [--preset P] [--set ...]`: one number of `hsp info --json` (e.g. `states`, \
         `jacobian.nonzeros`)",
        info_field,
    ),
    (
        "slow-pairs",
        "`slow-pairs K[-L] [--preset P] [--set ...]`: the K-th (to L-th) slowest complex \
         eigenvalue pairs of the model linearised at rest (`hsp linearize`), with frequency and \
         damping ratio",
        slow_pairs,
    ),
    (
        "model-description",
        "`model-description states|variables|outputs`: how many the repository's FMI 2.0 \
         `modelDescription.xml` declares (its `<Derivatives>`, its variables, its `<Outputs>`)",
        model_description,
    ),
    (
        "run-summary",
        "`run-summary [hsp run arguments]`: the summary `hsp run --no-build` prints on the \
         packaged FMU, without its wall-time line, as a text block",
        run_summary,
    ),
    (
        "fastest-move",
        "`fastest-move [hsp fastest-move arguments]`: what `hsp fastest-move --no-build` prints \
         on the packaged FMU (the fastest move within w_tip/a 0.1 and its torque budget), as a \
         text block",
        fastest_move,
    ),
    (
        "run-solver",
        "`run-solver [hsp run arguments]`: the solver counts of that run (steps, rejected, f \
         evaluations, Jacobians, LU factorisations)",
        run_solver,
    ),
    (
        "binary-size",
        "`binary-size FOLDER`: bytes of the packaged FMU's binary in `binaries/FOLDER/` (FMI 2.0 \
         folder names read the FMI 2.0 FMU); skipped unless the FMU has every portable binary",
        binary_size,
    ),
    (
        "web-size",
        "`web-size FILE`: bytes of `documentation/web/FILE` in the packaged FMU; skipped when \
         the FMU has no browser page",
        web_size,
    ),
];

/// Parses a block's arguments as those of the subcommand `hsp SUB`, with its own parser.
fn command(sub: &str, args: &[String]) -> Result<Command, String> {
    Cli::try_parse_from(
        ["hsp", sub]
            .into_iter()
            .map(String::from)
            .chain(args.iter().cloned()),
    )
    .map(|cli| cli.command)
    .map_err(|e| {
        format!("hsp {sub} {}: {}", args.join(" "), e.render())
            .trim()
            .into()
    })
}

/// The model arguments of `hsp SUB ARGS` (`modes`, `info`, `linearize`).
fn model_args(sub: &str, args: &[String]) -> Result<ModelArgs, String> {
    match command(sub, args)? {
        Command::Modes { model, .. }
        | Command::Info { model, .. }
        | Command::Linearize { model, .. } => Ok(model),
        _ => Err(format!("hsp {sub} has no model arguments")),
    }
}

/// `mode-hz (N,M) [model arguments]`.
fn mode_hz(_: &Context, args: &[String]) -> Result<Output, String> {
    let (label, rest) = args
        .split_first()
        .ok_or("mode-hz needs a mode label (N,M)")?;
    let model = model_args("modes", rest)?;
    let json: serde_json::Value =
        serde_json::from_str(&super::super::modes(&model, None, 0)?).map_err(|e| e.to_string())?;
    let labels = json["labels"].as_array().cloned().unwrap_or_default();
    let i = labels
        .iter()
        .position(|l| l.as_str() == Some(label))
        .ok_or_else(|| format!("hsp modes gives no mode {label}"))?;
    let f = json["f_hz"][i]
        .as_f64()
        .ok_or_else(|| format!("hsp modes gives no frequency for {label}"))?;
    Ok(Output::Text(format!("{f:.3}")))
}

/// `frf-peaks [hsp frf arguments]`.
fn frf_peaks(_: &Context, args: &[String]) -> Result<Output, String> {
    let Command::Frf {
        input,
        output,
        from,
        to,
        points,
        model,
        ..
    } = command("frf", args)?
    else {
        return Err("not hsp frf".into());
    };
    let json = super::super::frf(
        &super::super::FrfArgs {
            input: &input,
            output: &output,
            from,
            to,
            points,
            json: true,
            plot: None,
        },
        &model,
    )?;
    let h: serde_json::Value = serde_json::from_str(&json).map_err(|e| e.to_string())?;
    let peaks: Vec<String> = h["peaks"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|p| p[0].as_f64())
        .map(|f| format!("{f:.3}"))
        .collect();
    Ok(Output::Text(if peaks.is_empty() {
        "none".into()
    } else {
        peaks.join(", ")
    }))
}

/// `info FIELD [model arguments]`: FIELD a path into `hsp info --json`, parts joined by dots.
fn info_field(_: &Context, args: &[String]) -> Result<Output, String> {
    let (field, rest) = args
        .split_first()
        .ok_or("info needs a field of hsp info --json, e.g. states")?;
    let model = model_args("info", rest)?;
    let json: serde_json::Value = serde_json::from_str(&super::super::model_info(&model, true)?)
        .map_err(|e| e.to_string())?;
    let value = field
        .split('.')
        .try_fold(&json, |v, part| v.get(part))
        .ok_or_else(|| format!("hsp info --json has no field {field}"))?;
    Ok(Output::Text(match value {
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Array(a) => a
            .iter()
            .map(|v| v.as_str().map_or_else(|| v.to_string(), str::to_string))
            .collect::<Vec<_>>()
            .join(", "),
        v => v.to_string(),
    }))
}

/// `re ± im j` with four significant digits, the typographic minus and a plus on an unstable
/// pair.
fn pair_text(z: Complex<f64>) -> String {
    let sign = if z.re > 0.0 { "+" } else { "" };
    format!("{sign}{} ± {}j", num(z.re), num(z.im.abs())).replace('-', "−")
}

/// Two significant digits (a damping ratio), the typographic minus.
fn two_digits(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let decimals = (1 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.decimals$}").replace('-', "−")
}

/// Which of the slowest pairs: `K` (the K-th, from 1) or `K-L` (the K-th to the L-th).
fn pair_range(text: &str) -> Result<(usize, usize), String> {
    let bad =
        || format!("'{text}': expected K or K-L, the pairs counted from 1, the slowest first");
    let number = |s: &str| s.parse::<usize>().ok().filter(|&n| n > 0).ok_or_else(bad);
    let (first, last) = match text.split_once('-') {
        Some((a, b)) => (number(a)?, number(b)?),
        None => (number(text)?, number(text)?),
    };
    if first > last {
        return Err(bad());
    }
    Ok((first, last))
}

/// `slow-pairs K[-L] [hsp linearize arguments]`: the K-th (to L-th) slowest complex eigenvalue
/// pairs of the model linearised at rest, each with its frequency and damping ratio. The
/// eigenvalues are [`eigen::eigenvalues`] of A, balanced as LAPACK does: A in SI units is badly
/// scaled, and the QR iteration on A as it is errs in the slow pairs' real parts by up to 3 %.
fn slow_pairs(_: &Context, args: &[String]) -> Result<Output, String> {
    let (range, rest) = args
        .split_first()
        .ok_or("slow-pairs needs which pairs: K or K-L, from 1")?;
    let (first, last) = pair_range(range)?;
    let system = model_args("linearize", rest)?.assembled()?;
    let lin = system
        .compiled()
        .linearize(&system.initial_state(), system.inputs());
    let mut pairs: Vec<Complex<f64>> = eigen::eigenvalues(&lin.a)
        .into_iter()
        .filter(|z| z.im > 1e-9 * z.norm())
        .collect();
    pairs.sort_by(|x, y| x.norm().total_cmp(&y.norm()));
    let chosen: Vec<String> = pairs
        .iter()
        .skip(first - 1)
        .take(last + 1 - first)
        .map(|&z| {
            format!(
                "{} ({} Hz, ζ {})",
                pair_text(z),
                num(z.norm() / (2.0 * std::f64::consts::PI)),
                two_digits(-z.re / z.norm())
            )
        })
        .collect();
    if chosen.len() < last + 1 - first {
        return Err(format!(
            "the model has {} complex pairs, fewer than {last}",
            pairs.len()
        ));
    }
    Ok(Output::Text(chosen.join(", ")))
}

/// `model-description WHAT`.
fn model_description(_: &Context, args: &[String]) -> Result<Output, String> {
    let path = package::root().join("modelDescription/modelDescription.xml");
    let xml = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let md = ModelDescription::parse(&xml).map_err(|e| format!("{}: {e}", path.display()))?;
    let n = match args {
        [w] if w == "states" => md.structure.derivatives.len(),
        [w] if w == "variables" => md.variables.len(),
        [w] if w == "outputs" => md.structure.outputs.len(),
        _ => return Err("model-description needs one of states, variables, outputs".into()),
    };
    Ok(Output::Text(n.to_string()))
}

/// The packaged FMI 2.0 FMU under `root`, checked to be built from these sources.
fn fresh_fmu(ctx: &Context) -> Result<Result<PathBuf, String>, String> {
    let fmu = ctx.root.join(package::DEFAULT_FMU);
    if !fmu.exists() {
        return Ok(Err(format!(
            "{} does not exist (run `hsp package`)",
            fmu.display()
        )));
    }
    let binary = read_entry(&fmu, &format!("binaries/linux64/{MODEL_IDENTIFIER}.so"))?
        .ok_or_else(|| format!("{}: no binaries/linux64/", fmu.display()))?;
    let prefix = b"hsp-source-hash:";
    let hash = binary
        .windows(prefix.len())
        .position(|w| w == prefix)
        .and_then(|at| binary.get(at + prefix.len()..at + prefix.len() + SOURCE_HASH.len()));
    if hash != Some(SOURCE_HASH.as_bytes()) {
        return Err(format!(
            "{} is not built from these sources (this build's hash is {SOURCE_HASH}): run `hsp \
             package` first",
            fmu.display()
        ));
    }
    Ok(Ok(fmu))
}

/// Runs `hsp run --no-build` on the packaged FMU: the run's arguments, its summary.
fn run_on_fmu(
    ctx: &Context,
    name: &str,
    args: &[String],
) -> Result<Result<String, String>, String> {
    let Command::Run(run) = command("run", args)? else {
        return Err(format!("{name}: not hsp run"));
    };
    let fmu = match fresh_fmu(ctx)? {
        Ok(f) => f,
        Err(skip) => return Ok(Err(skip)),
    };
    run::summary_of(&run, &fmu).map(Ok)
}

/// `run-summary [hsp run arguments]`: the summary in a text block; the line `time ... wall, ...
/// x real time` is left out (it depends on the machine) and the results line names the CSV as
/// given (relative to the repository), not its absolute path.
fn run_summary(ctx: &Context, args: &[String]) -> Result<Output, String> {
    Ok(match run_on_fmu(ctx, "run-summary", args)? {
        Ok(s) => Output::Text(format!(
            "```text\n{}\n```",
            s.lines()
                .filter(|l| !l.starts_with(run::TIME_LINE))
                .collect::<Vec<_>>()
                .join("\n")
        )),
        Err(skip) => Output::Skip(skip),
    })
}

/// `fastest-move [hsp fastest-move arguments]`: its report in a text block.
fn fastest_move(ctx: &Context, args: &[String]) -> Result<Output, String> {
    let Command::FastestMove(a) = command("fastest-move", args)? else {
        return Err("fastest-move: not hsp fastest-move".into());
    };
    Ok(match fresh_fmu(ctx)? {
        Ok(fmu) => Output::Text(format!(
            "```text\n{}\n```",
            fastest::report(&a, &fmu)?.trim_end()
        )),
        Err(skip) => Output::Skip(skip),
    })
}

/// `run-solver [hsp run arguments]`: the counts of the summary's solver line.
fn run_solver(ctx: &Context, args: &[String]) -> Result<Output, String> {
    Ok(match run_on_fmu(ctx, "run-solver", args)? {
        Ok(s) => Output::Text(
            s.lines()
                .find_map(|l| l.strip_prefix(run::SOLVER_LINE))
                .ok_or("the summary has no solver line")?
                .to_string(),
        ),
        Err(skip) => Output::Skip(skip),
    })
}

/// The bytes of `name` in the zip archive `path`; `None` when it has no such entry.
fn read_entry(path: &Path, name: &str) -> Result<Option<Vec<u8>>, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut zip = zip::ZipArchive::new(file).map_err(|e| format!("{}: {e}", path.display()))?;
    let Ok(mut entry) = zip.by_name(name) else {
        return Ok(None);
    };
    let mut bytes = Vec::new();
    entry
        .read_to_end(&mut bytes)
        .map_err(|e| format!("{}: {name}: {e}", path.display()))?;
    Ok(Some(bytes))
}

/// The names of the entries of the zip archive `path`.
fn entries(path: &Path) -> Result<Vec<String>, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let zip = zip::ZipArchive::new(file).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(zip.file_names().map(str::to_string).collect())
}

/// A size in bytes as the docs print it: thousands separated by spaces.
fn bytes_text(n: usize) -> String {
    let digits = n.to_string();
    let mut s = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            s.push(' ');
        }
        s.push(c);
    }
    s
}

/// FMI 2.0's folder names; every other folder is FMI 3.0's.
const FMI2_FOLDERS: &[&str] = &["linux64", "win64", "darwin64"];

/// The binary whose presence says the package is the portable one (`--require-portable`): the
/// aarch64 Linux library is built by cargo-zigbuild like the glibc-2.17 x86-64 one, so with it
/// the Linux binaries are not the host-only build.
const PORTABLE_WITNESS: &str = "binaries/aarch64-linux/";

/// The one argument of a generator that reads the packaged FMUs, `Err(Skip)` when they are
/// missing.
fn fmu_argument<'a>(
    ctx: &Context,
    name: &str,
    args: &'a [String],
    example: &str,
) -> Result<Result<&'a str, Output>, String> {
    let [arg] = args else {
        return Err(format!("{name} needs one argument, e.g. {example}"));
    };
    Ok(match fresh_fmu(ctx)? {
        Ok(_) => Ok(arg.as_str()),
        Err(skip) => Err(Output::Skip(skip)),
    })
}

/// `binary-size FOLDER`.
fn binary_size(ctx: &Context, args: &[String]) -> Result<Output, String> {
    let folder = match fmu_argument(ctx, "binary-size", args, "x86_64-linux")? {
        Ok(f) => f,
        Err(skip) => return Ok(skip),
    };
    let fmi2 = ctx.root.join(package::DEFAULT_FMU);
    let fmi3 = package::fmi3_path(&fmi2);
    let fmu = if FMI2_FOLDERS.contains(&folder) {
        &fmi2
    } else {
        &fmi3
    };
    if !entries(&fmi3)?
        .iter()
        .any(|e| e.starts_with(PORTABLE_WITNESS))
    {
        return Ok(Output::Skip(format!(
            "{} has no {PORTABLE_WITNESS} (a --host-only or partial package): binary sizes \
             are those of `hsp package --require-portable`",
            fmi3.display()
        )));
    }
    if ctx.check && !folder.contains("linux") {
        // Measured: the same sources built in /work/main and in /work/ci-check gave macOS
        // binaries 48 to 832 bytes apart, and the Windows one 344 bytes apart in a second
        // build, while the Linux ones were equal to the byte each time. The crates' symbol
        // hashes depend on the checkout's path, and those linkers lay code and symbols out by
        // them.
        return Ok(Output::Skip(format!(
            "the size of binaries/{folder} depends on the checkout's path (the crates' symbol \
             hashes, which its linker lays out by), so `hsp docs` writes it and --check does \
             not compare it"
        )));
    }
    let prefix = format!("binaries/{folder}/");
    let names: Vec<String> = entries(fmu)?
        .into_iter()
        .filter(|e| e.starts_with(&prefix) && e.len() > prefix.len())
        .collect();
    let [name] = names.as_slice() else {
        return Ok(Output::Skip(format!(
            "{} has {} files in {prefix}",
            fmu.display(),
            names.len()
        )));
    };
    let bytes = read_entry(fmu, name)?.unwrap_or_default();
    Ok(Output::Text(bytes_text(bytes.len())))
}

/// `web-size FILE`.
fn web_size(ctx: &Context, args: &[String]) -> Result<Output, String> {
    let file = match fmu_argument(ctx, "web-size", args, "hsp.wasm")? {
        Ok(f) => f,
        Err(skip) => return Ok(skip),
    };
    let fmu = ctx.root.join(package::DEFAULT_FMU);
    Ok(
        match read_entry(&fmu, &format!("documentation/web/{file}"))? {
            Some(bytes) => Output::Text(bytes_text(bytes.len())),
            None => Output::Skip(format!(
                "{} has no documentation/web/{file} (packaged without the {} target)",
                fmu.display(),
                super::super::web::TARGET
            )),
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_grouped_by_thousands() {
        assert_eq!(bytes_text(926_458), "926 458");
        assert_eq!(bytes_text(1_752_464), "1 752 464");
        assert_eq!(bytes_text(12), "12");
    }
}
