//! The native side of `bench/web_speed.py` (not a test): the browser page's run, natively,
//! through the same API the `.wasm` exports (`hydraulic_slewing_plate::web::Simulation`), so that
//! the page's speed can be set beside the machine's.
//!
//! Reads JSON on stdin: `{"request": {"preset", "settings"}, "inputs": [r before each step],
//! "names": [outputs read after each step], "rounds": N, "step": h}` (what the page ran), and
//! prints `{"wall_s": [one per round], "last": [the outputs after the last step]}`. Each round
//! makes the simulation, steps it with `r` set before every step and reads the outputs after
//! every step, as the page does (its drawing aside).

use std::io::Read as _;
use std::time::Instant;

use hydraulic_slewing_plate::web::{parse_request, value_reference, Simulation};

fn main() -> Result<(), String> {
    let mut text = String::new();
    std::io::stdin()
        .read_to_string(&mut text)
        .map_err(|e| format!("stdin: {e}"))?;
    let job: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("stdin: {e}"))?;
    let (preset, settings) = parse_request(&job["request"].to_string())?;
    let inputs: Vec<f64> =
        serde_json::from_value(job["inputs"].clone()).map_err(|e| e.to_string())?;
    let names: Vec<String> =
        serde_json::from_value(job["names"].clone()).map_err(|e| e.to_string())?;
    let rounds = job["rounds"].as_u64().unwrap_or(5);
    let h = job["step"].as_f64().unwrap_or(1e-3);
    let refs = names
        .iter()
        .map(|n| value_reference(n).ok_or_else(|| format!("no variable '{n}'")))
        .collect::<Result<Vec<u32>, String>>()?;
    let r = value_reference("r").ok_or("no variable 'r'")?;
    let mut out = vec![0.0; refs.len()];
    let mut walls = Vec::new();
    for _ in 0..rounds {
        let start = Instant::now();
        let mut sim = Simulation::new(&preset, &settings)?;
        sim.get_reals(&refs, &mut out)?;
        for &input in &inputs {
            sim.set_real(r, input)?;
            sim.step(h)?;
            sim.get_reals(&refs, &mut out)?;
        }
        walls.push(start.elapsed().as_secs_f64());
    }
    println!("{}", serde_json::json!({"wall_s": walls, "last": out}));
    Ok(())
}
