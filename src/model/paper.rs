//! The numbers of the paper (Barbosa & Góes, 2002) that the model is meant to reproduce, as the
//! paper prints them, and where each belongs after the errata of docs/model-notes.md.
//!
//! The one copy of them: the tests (`tests/plate_modes.rs`, `tests/plate_coupled.rs`), the Bode
//! plot of `hsp frf --plot` and the validation report of `hsp validate` (docs/validation.md) read
//! them here. The identified transfer function of eq. 2 and the printed LOES constants belong to
//! the LOES fragment and are re-exported from there.

pub use crate::fragments::loes::{
    G_EST_GAIN, G_EST_POLE_1, G_EST_POLE_2, PRINTED_C3, PRINTED_I_B, PRINTED_R7,
};

/// A frequency as the paper prints it \[Hz\], with the number of decimals it prints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Printed {
    /// The printed value \[Hz\].
    pub hz: f64,
    /// Decimals printed (`4,91`: 2; `73`: 0).
    pub decimals: i32,
}

impl Printed {
    const fn new(hz: f64, decimals: i32) -> Self {
        Printed { hz, decimals }
    }

    /// Half a unit of the last printed digit: the largest difference from a value that the
    /// paper would have printed this way.
    pub fn half_unit(&self) -> f64 {
        0.5 * 10f64.powi(-self.decimals)
    }

    /// Whether `value` rounds to the printed number (to the printed decimals; the bound is
    /// widened by 1e-9 relative for the binary representation of the printed decimal).
    pub fn rounds_to(&self, value: f64) -> bool {
        (value - self.hz).abs() <= self.half_unit() + 1e-9 * self.hz.abs()
    }
}

/// One frequency of eq. 16 and the plate mode `(n, m)` it belongs to (docs/model-notes.md,
/// item 1: eq. 21's diagonal stiffness reproduces six of them); `None` for the 56.8 Hz that
/// eq. 21 does not give (item 2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eq16Frequency {
    pub printed: Printed,
    pub mode: Option<(usize, usize)>,
}

/// Eq. 16: "the first mode frequencies of the system, arranged in descending order", Hz, in the
/// paper's order.
pub const EQ16: [Eq16Frequency; 7] = [
    Eq16Frequency {
        printed: Printed::new(86.1, 1),
        mode: Some((3, 3)),
    },
    Eq16Frequency {
        printed: Printed::new(73.5, 1),
        mode: Some((2, 3)),
    },
    Eq16Frequency {
        printed: Printed::new(66.8, 1),
        mode: Some((1, 3)),
    },
    Eq16Frequency {
        printed: Printed::new(56.8, 1),
        mode: None,
    },
    Eq16Frequency {
        printed: Printed::new(33.2, 1),
        mode: Some((3, 1)),
    },
    Eq16Frequency {
        printed: Printed::new(15.9, 1),
        mode: Some((2, 1)),
    },
    Eq16Frequency {
        printed: Printed::new(4.91, 2),
        mode: Some((1, 1)),
    },
];

/// One row of Table 1 ("resonance frequencies of the flexible system"). Its first column
/// ("analytical frequencies") repeats eq. 16 for the row's mode, except the misprint
/// [`TABLE1_MISPRINT`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Table1Row {
    /// The plate mode `(n, m)` of the row (the paper's conclusion assigns them).
    pub mode: (usize, usize),
    /// Second column: resonance peak of the computed FRF of Fig. 9b (from `r` to the tip, hub
    /// driven by the LOES through the torsion bar).
    pub fig9b: Printed,
    /// Third column: resonance peak of the experimental FRFs of Fig. 10 (hub locked, plate
    /// shaken); `None` where the paper prints "*" (out of the analysed band).
    pub experiment: Option<Printed>,
}

/// Table 1, in the paper's order.
pub const TABLE1: [Table1Row; 6] = [
    Table1Row {
        mode: (1, 1),
        fig9b: Printed::new(4.98, 2),
        experiment: Some(Printed::new(5.0, 1)),
    },
    Table1Row {
        mode: (2, 1),
        fig9b: Printed::new(16.0, 1),
        experiment: Some(Printed::new(19.0, 1)),
    },
    Table1Row {
        mode: (3, 1),
        fig9b: Printed::new(33.3, 1),
        experiment: Some(Printed::new(33.0, 1)),
    },
    Table1Row {
        mode: (1, 3),
        fig9b: Printed::new(66.0, 1),
        experiment: None,
    },
    Table1Row {
        mode: (2, 3),
        fig9b: Printed::new(73.0, 0),
        experiment: None,
    },
    Table1Row {
        mode: (3, 3),
        fig9b: Printed::new(84.0, 0),
        experiment: None,
    },
];

/// Table 1's first column prints `4,41` for the (1,1) mode: a misprint of eq. 16's 4.91
/// (docs/model-notes.md, item 5). `(printed, meant)`, Hz.
pub const TABLE1_MISPRINT: (f64, f64) = (4.41, 4.91);

/// Table 1, second column: the resonance peaks of the paper's FRF of Fig. 9b, Hz, in the table's
/// order (the reference marks of `hsp frf --plot`).
pub const TABLE1_FRF_HZ: [f64; 6] = {
    let mut out = [0.0; 6];
    let mut i = 0;
    while i < TABLE1.len() {
        out[i] = TABLE1[i].fig9b.hz;
        i += 1;
    }
    out
};

/// The eq. 16 frequency of a plate mode, if eq. 16 gives one.
pub fn eq16_of(mode: (usize, usize)) -> Option<Printed> {
    EQ16.iter()
        .find(|f| f.mode == Some(mode))
        .map(|f| f.printed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_to_the_printed_digits() {
        let p = Printed::new(86.1, 1);
        assert!(p.rounds_to(86.055) && p.rounds_to(86.149));
        assert!(!p.rounds_to(86.16) && !p.rounds_to(86.04));
        assert!(Printed::new(73.0, 0).rounds_to(73.4));
        assert_eq!(TABLE1_FRF_HZ[4], TABLE1[4].fig9b.hz);
        assert_eq!(eq16_of((1, 1)).map(|p| p.hz), Some(4.91));
        assert_eq!(eq16_of((3, 2)), None);
    }
}
