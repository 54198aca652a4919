//! The Newtonian viscous stress (E46) any material may add to its model's.

use super::volume_ratio_minus_one;
use crate::layout::MaterialRecord;
use crate::Real;

/// Adds the Newtonian viscous stress of each lane's material to the chunk's `tau / rho0` (E46):
/// `tau_visc = J sigma_visc`, `sigma_visc = eta (L + L^T - 2/3 tr(L) I) + zeta tr(L) I` with
/// `L = grad v` (`l[a][b][lane]`) and, in 2D, the out-of-plane rate `lzz` (`v_r / r`
/// axisymmetric, 0 in plane strain), which enters the trace and `zz`. Lanes of materials
/// without viscosity, or of no material, get nothing.
#[inline(always)]
pub(crate) fn add_viscous_lanes<const D: usize, const W: usize>(
    materials: &[MaterialRecord],
    ids: &[u32; W],
    l: &[[[Real; W]; D]; D],
    lzz: &[Real; W],
    jm1: &[Real; W],
    plastic: &[Real; W],
    tau: &mut [[Real; W]; 6],
) {
    for ln in 0..W {
        // `J eta / rho0` and `J zeta / rho0` with the particle's whole volume ratio (snow's
        // `J_e J_p`).
        let (k, kb) = materials.get(ids[ln] as usize).map_or((0.0, 0.0), |r| {
            let j = 1.0 + volume_ratio_minus_one(r, jm1[ln], plastic[ln]);
            (
                r.viscosity / r.density * j,
                r.bulk_viscosity / r.density * j,
            )
        });
        let mut tr = if D == 2 { lzz[ln] } else { 0.0 };
        for a in 0..D {
            tr += l[a][a][ln];
        }
        // The bulk part is added on its own, before the shear part: with `zeta = 0` it adds
        // 0 and the shear viscosity's stress keeps its bits.
        let (third, bulk) = (tr * (2.0 / 3.0), kb * tr);
        for (c, &(a, b)) in crate::layout::sym_pairs(D).iter().enumerate() {
            let mut s = l[a][b][ln] + l[b][a][ln];
            if a == b {
                s -= third;
                tau[c][ln] += bulk;
            }
            tau[c][ln] += k * s;
        }
        if D == 2 {
            tau[3][ln] += bulk;
            tau[3][ln] += k * (2.0 * lzz[ln] - third);
        }
    }
}
