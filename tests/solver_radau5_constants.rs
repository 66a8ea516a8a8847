//! The RADAU5 constants in src/solver/radau5/coefficients.rs: T, T⁻¹ and the eigenvalues of A⁻¹ must match
//! the Radau IIA coefficient matrix A (Hairer & Wanner II, Table IV.5.6).

// Wrapped in a module so that `cargo test solver` selects these tests by name.
mod solver_radau5_constants {
    use hydraulic_slewing_plate::solver::radau5::{inverse_eigenvalues, nodes, T, TI};
    use nalgebra::Matrix3;

    fn radau_iia_a() -> Matrix3<f64> {
        let s = 6f64.sqrt();
        Matrix3::new(
            (88.0 - 7.0 * s) / 360.0,
            (296.0 - 169.0 * s) / 1800.0,
            (-2.0 + 3.0 * s) / 225.0,
            (296.0 + 169.0 * s) / 1800.0,
            (88.0 + 7.0 * s) / 360.0,
            (-2.0 - 3.0 * s) / 225.0,
            (16.0 - s) / 36.0,
            (16.0 + s) / 36.0,
            1.0 / 9.0,
        )
    }

    #[test]
    fn t_times_ti_is_identity() {
        let t = Matrix3::from_fn(|i, j| T[i][j]);
        let ti = Matrix3::from_fn(|i, j| TI[i][j]);
        assert!((t * ti - Matrix3::identity()).abs().max() < 1e-14);
    }

    #[test]
    fn t_block_diagonalises_a_inverse() {
        let a = radau_iia_a();
        let ainv = a.try_inverse().unwrap();
        let t = Matrix3::from_fn(|i, j| T[i][j]);
        let ti = Matrix3::from_fn(|i, j| TI[i][j]);
        let (g, al, be) = inverse_eigenvalues();
        let expect = Matrix3::new(g, 0.0, 0.0, 0.0, al, -be, 0.0, be, al);
        let got = ti * ainv * t;
        assert!((got - expect).abs().max() < 1e-12, "TI A^-1 T = {got}");
    }

    #[test]
    fn nodes_are_row_sums_of_a() {
        let a = radau_iia_a();
        let (c1, c2) = nodes();
        let rs: Vec<f64> = (0..3).map(|i| a.row(i).sum()).collect();
        assert!(
            (rs[0] - c1).abs() < 1e-15 && (rs[1] - c2).abs() < 1e-15 && (rs[2] - 1.0).abs() < 1e-15
        );
    }
}
