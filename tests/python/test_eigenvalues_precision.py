"""The eigenvalues that `hsp linearize --json` prints (src/eigen.rs: A balanced as LAPACK's dgebal
does, then nalgebra's QR) against the eigenvalues of the same A computed with 40 digits (mpmath),
to 1e-4 of each real and each imaginary part. A in SI units is badly scaled (entries from 1e-31 to
3e11); nalgebra's QR on it unbalanced misses the slow pairs' real parts by 1 to 3 %, and with
`plate.zeta = 0` it puts the undamped plate modes' real parts at 6e-8 instead of 1e-12 (both
measured on 2026-12-06)."""

import json

import mpmath
import pytest

from conftest import hsp

CASES = {
    "default": [],
    # The structure undamped: the slow pairs unstable, the higher plate modes with real parts of
    # 1e-12 s⁻¹.
    "plate.zeta=0": ["--set", "plate.zeta=0"],
}

# Relative tolerance of each part.
RTOL = 1e-4
# An absolute floor, as a fraction of the largest |λ|, for the parts that are zero or tiny: the
# imaginary parts of the real eigenvalues and both parts of the free integrators' zeros (exact
# zeros in the printed values, round-off of 1e-35 in the 40-digit ones), and, with
# `plate.zeta = 0`, the real parts of 1e-12 of the undamped plate modes at |λ| ~ 2e3. A double
# carries about 16 digits of the largest eigenvalue (6e4 s⁻¹): no double-precision method
# resolves a part below 1e-14 of it (6e-10 s⁻¹), and the balanced QR errs by 1.4e-12 s⁻¹ there
# (the unbalanced one by 6e-8). The floor is far below every physical part (RTOL of the slowest
# real part, 0.0076 s⁻¹, is 7.6e-7 s⁻¹), so it does not loosen those.
FLOOR = 1e-14


def reference(a):
    """The eigenvalues of `a` at 40 digits (no eigenvectors: 4 s for the 45 x 45)."""
    with mpmath.workdps(40):
        return [complex(z) for z in mpmath.eig(mpmath.matrix(a), left=False, right=False)]


@pytest.mark.parametrize("case", CASES)
def test_printed_eigenvalues_match_40_digits(case):
    lin = json.loads(hsp("linearize", "--json", *CASES[case]))
    a = lin["A"]
    printed = [complex(re, im) for re, im in lin["eigenvalues"]]
    assert len(printed) == len(a) == len(lin["states"]), (len(printed), len(a))
    want = reference(a)
    floor = FLOOR * max(abs(w) for w in want)
    # Each printed eigenvalue paired with the nearest 40-digit one not yet taken, so that a
    # double eigenvalue (the two zeros) needs two.
    left = list(want)
    for z in printed:
        w = min(left, key=lambda w: abs(w - z))
        left.remove(w)
        assert abs(z.real - w.real) <= RTOL * abs(w.real) + floor, (case, z, w)
        assert abs(z.imag - w.imag) <= RTOL * abs(w.imag) + floor, (case, z, w)
        # A pair's members are exact conjugates, a real eigenvalue is real.
        assert complex(z.real, -z.imag) in printed, (case, z)
    # The order: the largest real part first, then the largest imaginary part.
    keys = [(-z.real, -z.imag) for z in printed]
    assert keys == sorted(keys), case
