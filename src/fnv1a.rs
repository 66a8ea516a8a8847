//! FNV-1a, 64 bits, and the model description's GUID made from it: the one copy of both rules.
//!
//! The library uses the hash as a checksum; `build.rs` includes this very file (`#[path =
//! "src/fnv1a.rs"] mod fnv1a;`) to check the GUID of `modelDescription.xml`, and so does
//! `tools/guid.rs`, the small program that `modelDescription/update.py` compiles with `rustc`
//! and runs to write the GUID (it needs no build of the crate, which fails while the GUID is
//! stale). The file uses nothing outside the standard library, so that each of them can include it.

/// The offset basis of 64-bit FNV-1a: the hash of no bytes.
pub const OFFSET_BASIS: u64 = 0xcbf2_9ce4_8422_2325;

/// The 64-bit FNV prime.
pub const PRIME: u64 = 0x0000_0100_0000_01b3;

/// FNV-1a over bytes, from [`OFFSET_BASIS`].
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    fnv1a64_from(OFFSET_BASIS, bytes)
}

/// FNV-1a over bytes, starting from `hash`: another offset basis, or the hash of the bytes before
/// these (hashing a sequence piece by piece gives the hash of the whole).
pub fn fnv1a64_from(hash: u64, bytes: &[u8]) -> u64 {
    let mut hash = hash;
    for b in bytes {
        hash ^= u64::from(*b);
        hash = hash.wrapping_mul(PRIME);
    }
    hash
}

/// The second offset basis of the GUID: [`OFFSET_BASIS`] with its halves swapped.
pub const GUID_BASIS: u64 = 0x8422_2325_cbf2_9ce4;

/// The GUID `modelDescription.xml` must carry: two FNV-1a hashes (offset bases [`OFFSET_BASIS`]
/// and [`GUID_BASIS`]) of the file's text with the value of its `guid` attribute, `current`,
/// blanked (the first `guid="current"` becomes `guid=""`), written in the 8-4-4-4-12 form with
/// braces. It changes whenever anything else in the file does.
pub fn model_guid(text: &str, current: &str) -> String {
    let blanked = text.replacen(&format!("guid=\"{current}\""), "guid=\"\"", 1);
    let a = fnv1a64(blanked.as_bytes());
    let b = fnv1a64_from(GUID_BASIS, blanked.as_bytes());
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a64_from(fnv1a64(b"ab"), b"c"), fnv1a64(b"abc"));
        assert_eq!(OFFSET_BASIS.rotate_left(32), GUID_BASIS);
    }

    #[test]
    fn the_guid_ignores_its_own_value() {
        let text = "<a guid=\"{x}\" b=\"1\"/>";
        let guid = model_guid(text, "{x}");
        assert_eq!(guid, model_guid("<a guid=\"\" b=\"1\"/>", ""));
        assert_eq!(guid.len(), 38);
        assert_ne!(guid, model_guid("<a guid=\"\" b=\"2\"/>", ""));
    }
}
