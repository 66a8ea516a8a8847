//! FMU states (`fmi2GetFMUstate` and its siblings): what one holds, its serialised form, and the
//! check that a pointer the environment hands back is one of ours.
//!
//! A serialised state is magic bytes, the payload's length and FNV-1a checksum, then the JSON
//! payload. The checksum only catches accidents: anyone can recompute it, so a restored state is
//! validated afterwards as strictly as fresh input (see `Instance::restore`).

use serde::{Deserialize, Serialize};

use super::calls::MachineState;
use super::variables::Values;
use super::Experiment;
use crate::fnv1a::fnv1a64;

/// What an FMU state holds: everything needed to continue bit-identically.
#[derive(Clone, Serialize, Deserialize)]
pub struct Snapshot<S> {
    pub guid: String,
    /// The state of the state machine the FMU state was taken in.
    pub state: MachineState,
    pub time: f64,
    pub last_successful_time: f64,
    pub experiment: Experiment,
    pub values: Values,
    pub needs_initialize: bool,
    pub model: S,
}

/// Magic bytes at the start of a serialised FMU state, followed by the digit of its format
/// version ([`STATE_FORMAT`]).
const SERIAL_MAGIC: &[u8; 7] = b"HSPFMUS";
const SERIAL_HEADER: usize = 8 + 8 + 8;

/// The version of the serialised FMU state's format, the eighth byte of its header as an ASCII
/// digit. Raised with any change of the payload's layout that an older reader would misread;
/// within it, the solver method's state carries a version of its own (`state_version`, written
/// and checked by the method). 1: the payload of issue 24; 2: the solver's state as the shared
/// point and the method's own versioned state (issue 40).
pub const STATE_FORMAT: u8 = 2;

/// Guards against pointers that are not FMU states of this library (an instance, say, or a state
/// already freed).
const STATE_MAGIC: u64 = 0x4853_505f_5354_4154; // "HSP_STAT"

/// A saved FMU state, with its serialised form computed once when asked for. `repr(C)` puts the
/// magic number first, so that a pointer can be checked before a reference is made.
#[repr(C)]
pub struct SavedState<S> {
    magic: u64,
    pub snapshot: Snapshot<S>,
    serialized: Option<Vec<u8>>,
}

impl<S: Serialize + for<'de> Deserialize<'de>> SavedState<S> {
    pub fn new(snapshot: Snapshot<S>) -> Self {
        SavedState {
            magic: STATE_MAGIC,
            snapshot,
            serialized: None,
        }
    }

    /// Whether `ptr` looks like a state made by [`SavedState::new`] and not yet freed. Reads only
    /// the leading magic number.
    ///
    /// # Safety
    /// `ptr` is non-null and points to at least 8 readable bytes.
    pub unsafe fn is_saved_state(ptr: *const Self) -> bool {
        // SAFETY: the caller guarantees 8 readable bytes at `ptr`; `magic` is the first field of
        // this `repr(C)` struct, read unaligned without a reference to the rest.
        unsafe { std::ptr::addr_of!((*ptr).magic).read_unaligned() == STATE_MAGIC }
    }

    /// Marks the state freed so that a dangling use is caught while the memory is still ours.
    pub fn invalidate(&mut self) {
        self.magic = 0;
    }

    /// The serialised form: magic, payload length, payload checksum, JSON payload.
    pub fn serialized(&mut self) -> Result<&[u8], String> {
        if self.serialized.is_none() {
            let payload = serde_json::to_vec(&self.snapshot)
                .map_err(|e| format!("cannot serialise the FMU state: {e}"))?;
            let mut bytes = Vec::with_capacity(SERIAL_HEADER + payload.len());
            bytes.extend_from_slice(SERIAL_MAGIC);
            bytes.push(b'0' + STATE_FORMAT);
            bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
            bytes.extend_from_slice(&fnv1a64(&payload).to_le_bytes());
            bytes.extend_from_slice(&payload);
            self.serialized = Some(bytes);
        }
        Ok(self.serialized.as_deref().unwrap_or_default())
    }

    /// Reads a serialised state, checking its header and format version, length, checksum and
    /// GUID.
    pub fn deserialize(bytes: &[u8], guid: &str) -> Result<Self, String> {
        if bytes.len() < SERIAL_HEADER || &bytes[..7] != SERIAL_MAGIC || !bytes[7].is_ascii_digit()
        {
            return Err(format!(
                "the serialized FMU state ({} bytes) does not start with this FMU's header",
                bytes.len()
            ));
        }
        let format = bytes[7] - b'0';
        if format != STATE_FORMAT {
            return Err(format!(
                "the serialized FMU state is of format version {format}, this FMU reads format version {STATE_FORMAT}"
            ));
        }
        let len = u64::from_le_bytes(bytes[8..16].try_into().unwrap_or_default());
        let sum = u64::from_le_bytes(bytes[16..24].try_into().unwrap_or_default());
        let payload = &bytes[SERIAL_HEADER..];
        if payload.len() as u64 != len {
            return Err(format!(
                "the serialized FMU state is truncated or padded: header says {len} payload bytes, got {}",
                payload.len()
            ));
        }
        if fnv1a64(payload) != sum {
            return Err("the serialized FMU state is corrupted: checksum mismatch".to_string());
        }
        let snapshot: Snapshot<S> = serde_json::from_slice(payload)
            .map_err(|e| format!("the serialized FMU state cannot be read: {e}"))?;
        if snapshot.guid != guid {
            return Err(format!(
                "the serialized FMU state belongs to GUID {}, not to this FMU ({guid})",
                bounded(&snapshot.guid)
            ));
        }
        Ok(SavedState::new(snapshot))
    }
}

/// The most characters of a crafted text a message quotes.
pub const QUOTED_CHARS: usize = 64;

/// `text` as a message quotes it: whole up to [`QUOTED_CHARS`] characters, else its start and
/// its length (a crafted state's 10 MB GUID is not copied into the log).
pub fn bounded(text: &str) -> String {
    match text.char_indices().nth(QUOTED_CHARS) {
        None => text.to_string(),
        Some((cut, _)) => format!("{}... ({} bytes)", &text[..cut], text.len()),
    }
}

#[cfg(test)]
mod quoting_tests {
    use super::*;

    #[test]
    fn long_texts_are_quoted_by_their_start_and_length() {
        assert_eq!(bounded("{abc}"), "{abc}");
        let long = "x".repeat(10_000_000);
        let q = bounded(&long);
        assert!(q.starts_with(&"x".repeat(QUOTED_CHARS)) && q.ends_with("... (10000000 bytes)"));
        assert!(q.len() < 100);
        // cut on a character boundary
        let wide = "é".repeat(100);
        assert_eq!(
            bounded(&wide),
            format!("{}... (200 bytes)", "é".repeat(QUOTED_CHARS))
        );
    }
}
