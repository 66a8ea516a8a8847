//! splitmix64 (Steele, Lea and Flood, "Fast splittable pseudorandom number generators", 2014):
//! a seed's stream of uniform numbers, the one copy of the rule. `hsp identify --starts` draws
//! its starting points with it and `tests/identify.rs` its synthetic noise; each includes this
//! file (`#[path = ...] mod splitmix64;`), which uses nothing outside the core language.

/// The generator's state; `SplitMix64(seed)` starts a stream.
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next uniform number in [0, 1), 53 random bits.
    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}
