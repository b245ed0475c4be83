//! The README's table of exact values matches the model (as printed by `examples/value_table.rs`), and
//! each L+ and L− in it matches the independent view-ray quadrature.

use sheer_slab::IrradianceConvention;
use sheer_slab::csv::{REFERENCE_TABLE_INPUTS, evaluate_row, markdown_row};
use sheer_slab::reference::single_scattered_radiance_by_view_ray_quadrature;

#[test]
fn readme_table_is_current_and_matches_quadrature() {
    let readme = include_str!("../README.md");
    for [tau1, albedo, mu0, mu] in REFERENCE_TABLE_INPUTS {
        let row = evaluate_row(
            &format!("{tau1},{albedo},{mu0},{mu}"),
            IrradianceConvention::NormalToBeam,
        )
        .unwrap();
        let line = markdown_row(&row);
        assert!(
            readme.contains(&line),
            "README lacks the row\n{line}\n(regenerate with the value_table example)"
        );
        for (lit_side, value) in [(true, row.l_plus), (false, row.l_minus)] {
            let quadrature = single_scattered_radiance_by_view_ray_quadrature(
                tau1, albedo, mu0, mu, 1.0, lit_side,
            )
            .unwrap();
            // Quadrature is exact to rounding of its ≤ 4·10^5 positive terms (see model_numerics.rs): 1e-11.
            assert!(
                (value - quadrature).abs() <= 1e-11 * quadrature + 1e-300,
                "row {line}: {value:e} vs quadrature {quadrature:e}"
            );
        }
    }
}
