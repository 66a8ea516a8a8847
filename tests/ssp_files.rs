//! The committed SSP files in `ssp/` (the presets as parameter sets, the example system) are what
//! `hsp ssp` writes from `src/model/presets.rs`, to the byte, and no file there is left over from
//! a preset that is gone. After changing a preset, run `hsp ssp` and commit `ssp/`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Every file under `dir`, by its path relative to `dir`.
fn files(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let rel = path.strip_prefix(dir).unwrap().to_path_buf();
                out.insert(rel, std::fs::read(&path).unwrap());
            }
        }
    }
    out
}

#[test]
fn committed_ssp_files_are_what_hsp_ssp_writes() {
    let tmp = std::env::temp_dir().join(format!("hsp-ssp-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    let out = Command::new(env!("CARGO_BIN_EXE_hsp"))
        .args(["ssp", "--out"])
        .arg(&tmp)
        .output()
        .expect("cannot run hsp");
    assert!(
        out.status.success(),
        "hsp ssp failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let written = files(&tmp);
    let _ = std::fs::remove_dir_all(&tmp);
    let committed = files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("ssp"));
    assert!(written.len() > 2, "hsp ssp wrote only {:?}", written.keys());
    assert_eq!(
        written.keys().collect::<Vec<_>>(),
        committed.keys().collect::<Vec<_>>(),
        "ssp/ holds other files than hsp ssp writes: run `hsp ssp`"
    );
    for (name, bytes) in &written {
        assert!(
            committed[name] == *bytes,
            "ssp/{} differs from what hsp ssp writes: run `hsp ssp`",
            name.display()
        );
    }
}
