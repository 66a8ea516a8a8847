//! Serialised FMU states as a hostile importer edits them: the JSON payload of a blob, and a blob
//! from an edited payload with its checksum recomputed (the format is the core's, the same in
//! both FMI versions).

#![allow(dead_code)]

use hydraulic_slewing_plate::fnv1a::fnv1a64;

/// A serialised state's JSON payload.
pub fn payload(bytes: &[u8]) -> serde_json::Value {
    serde_json::from_slice(&bytes[24..]).unwrap()
}

pub fn blob(payload: &serde_json::Value) -> Vec<u8> {
    let p = serde_json::to_vec(payload).unwrap();
    let mut b = b"HSPFMUS".to_vec();
    b.push(b'0' + hydraulic_slewing_plate::fmu::fmu_state::STATE_FORMAT);
    b.extend_from_slice(&(p.len() as u64).to_le_bytes());
    b.extend_from_slice(&fnv1a64(&p).to_le_bytes());
    b.extend_from_slice(&p);
    b
}

/// The first value under `key` anywhere in `v` (a state payload, say).
pub fn find_key<'a>(v: &'a mut serde_json::Value, key: &str) -> Option<&'a mut serde_json::Value> {
    match v {
        serde_json::Value::Object(m) => {
            if m.contains_key(key) {
                return m.get_mut(key);
            }
            m.values_mut().find_map(|x| find_key(x, key))
        }
        serde_json::Value::Array(a) => a.iter_mut().find_map(|x| find_key(x, key)),
        _ => None,
    }
}
