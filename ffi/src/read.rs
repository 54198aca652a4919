//! Reading state from C: a borrowed view of the particle columns, copy-out functions into
//! caller buffers, and the world's sums (mass, momentum, energies).

use crate::status::MpmStatus;
use crate::world::{put, world_ref, MpmWorld};
use crate::{apart, guard, mpm_real, non_null};
use kernel::{ParticlesView, WorldRef};

/// Borrowed view of every particle column, from `mpm_world_particles`. Valid until the next
/// call that changes the world (add, seed, set, step) or frees its memory. Pointers of axes the
/// dimension lacks (z in 2D), of effects the definition does not declare, and `hoop` unless the
/// world is axisymmetric, are NULL; every other column holds `count` values.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct MpmParticlesView {
    /// Number of particles.
    pub count: usize,
    /// The world's dimension.
    pub dimension: crate::MpmDimensionValue,
    /// Positions per axis, m, rounded to `mpm_real`.
    pub position: [*const mpm_real; 3],
    /// What rounding the positions left out, per axis, m (at most one unit in the last place
    /// of the position; half of one once it has moved less than its distance from the origin
    /// in a step; `mpm_world_open` refuses more): `position + position_low`, summed in double, is the position to twice
    /// `mpm_real`'s precision. The step moves a particle by this pair, so that a displacement
    /// below the last bit of a coordinate is not lost (in float, 1 um at 10 m).
    pub position_low: [*const mpm_real; 3],
    /// Velocities per axis, m/s.
    pub velocity: [*const mpm_real; 3],
    /// Masses, kg (per unit thickness in plane strain, per radian when axisymmetric).
    pub mass: *const mpm_real,
    /// Initial volumes, m^3 (m^2 per unit thickness in plane strain, m^3 per radian when
    /// axisymmetric).
    pub volume0: *const mpm_real,
    /// Displacement gradient H = F - I, entry (a, b) at index `3 a + b`; 2D uses a, b < 2.
    pub displacement_gradient: [*const mpm_real; 9],
    /// Kirchhoff stress over initial density, m^2/s^2: 2D xx, yy, xy, zz (axisymmetric: rr, zz,
    /// rz, thetatheta); 3D xx, yy, zz, xy, xz, yz (the last two NULL in 2D).
    pub stress: [*const mpm_real; 6],
    /// Material ids.
    pub material: *const u32,
    /// Statuses (`MpmParticleStatus`).
    pub status: *const u32,
    /// External forces per axis, N (NULL unless `MpmEffects::particle_forces`).
    pub force: [*const mpm_real; 3],
    /// Local grid and particle damping alpha_g, alpha_p, 1/s (NULL unless
    /// `MpmDamping::per_particle`).
    pub damping: [*const mpm_real; 2],
    /// APIC moment matrix B_p, m^2/s, entry (a, b) at index `3 a + b`; 2D uses a, b < 2 (NULL
    /// unless the transfer is `MPM_TRANSFER_APIC` or `MPM_TRANSFER_MLS`). The affine velocity field is
    /// `C_p = B_p D_p^-1`, with D_p the second moment of the particle's weights where it next
    /// scatters.
    pub affine: [*const mpm_real; 9],
    /// Temperatures, K (NULL unless `MpmEffects::heat`).
    pub temperature: *const mpm_real,
    /// Concentration potentials c / c_sat (NULL unless `MpmEffects::diffusion`).
    pub concentration: *const mpm_real,
    /// The grid's temperature at each particle after the last step, K: what a feature that
    /// depends on temperature should read, since the particles' own values keep any variation
    /// within a cell (NULL unless `MpmEffects::heat`).
    pub grid_temperature: *const mpm_real,
    /// The grid's concentration potential at each particle after the last step (NULL unless
    /// `MpmEffects::diffusion`).
    pub grid_concentration: *const mpm_real,
    /// The hoop stretch F_thetatheta - 1 = r / r_0 - 1, the out-of-plane part of the
    /// deformation gradient (NULL unless the dimension is `MPM_DIMENSION_AXISYMMETRIC2D`).
    pub hoop: *const mpm_real,
    /// The plastic history: the equivalent plastic strain (von Mises), the accumulated plastic
    /// shear (Drucker-Prager), J_p - 1 (snow); 0 for other models (NULL unless
    /// `MpmEffects::plasticity`).
    pub plastic: *const mpm_real,
    /// Heat sources, W/m^3 (NULL unless `MpmEffects::heat` with `sources`).
    pub temperature_source: *const mpm_real,
    /// Sources of the concentration potential, 1/s (NULL unless `MpmEffects::diffusion` with
    /// `sources`).
    pub concentration_source: *const mpm_real,
}

/// Sums over the active particles, in double precision. In plane strain mass, momentum and
/// energies are per metre of thickness; axisymmetric, per radian.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct MpmDiagnostics {
    /// Number of particles added (any status).
    pub particle_count: usize,
    /// Simulated time, s.
    pub time: f64,
    /// Successful steps (it stays at 2^64 - 1 once there: it does not wrap).
    pub step_count: u64,
    /// Mass of the active particles, kg.
    pub mass: f64,
    /// Linear momentum, kg m/s.
    pub momentum: [f64; 3],
    /// Angular momentum about the origin, kg m^2/s (2D: the z component only); with APIC it
    /// includes each particle's affine part.
    pub angular_momentum: [f64; 3],
    /// Centre of mass, m.
    pub center_of_mass: [f64; 3],
    /// Kinetic energy, J; with APIC and MLS-MPM it includes each particle's affine velocity
    /// field, as the angular momentum does.
    pub kinetic: f64,
    /// Strain energy, J.
    pub strain: f64,
    /// Gravitational potential energy (zero at the origin), J.
    pub potential: f64,
}

/// The particle columns of `world` in `view_out`.
///
/// # Safety
/// `world` is NULL or a world; `view_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_particles(
    world: *const MpmWorld,
    view_out: *mut MpmParticlesView,
) -> MpmStatus {
    guard(|| {
        non_null(view_out)?;
        // SAFETY: the caller promises a world.
        let w = unsafe { world_ref(world) }?;
        apart(w.as_bytes(), view_out, 1)?;
        let v = w.particles();
        let def = w.def();
        let d = def.axes();
        let axis = |s: &[mpm_real], used: bool| if used { s.as_ptr() } else { core::ptr::null() };
        let forces = def.effects.particle_forces;
        let per_particle = def.effects.damping.is_some_and(|dm| dm.per_particle);
        let apic = def.transfer.is_affine();
        let heat = def.effects.heat.is_some();
        let diffusion = def.effects.diffusion.is_some();
        let axisymmetric = def.dimension == kernel::Dimension::Axisymmetric2D;
        let sources = |t: Option<kernel::Transport>| t.is_some_and(|t| t.sources);
        let out = MpmParticlesView {
            count: v.count,
            dimension: v.dimension as u32,
            position: core::array::from_fn(|a| axis(v.position[a], a < d)),
            position_low: core::array::from_fn(|a| axis(v.position_low[a], a < d)),
            velocity: core::array::from_fn(|a| axis(v.velocity[a], a < d)),
            mass: v.mass.as_ptr(),
            volume0: v.volume0.as_ptr(),
            displacement_gradient: core::array::from_fn(|k| {
                axis(
                    v.displacement_gradient[k / 3][k % 3],
                    k / 3 < d && k % 3 < d,
                )
            }),
            stress: core::array::from_fn(|k| axis(v.stress[k], k < if d == 3 { 6 } else { 4 })),
            material: v.material.as_ptr(),
            status: v.status.as_ptr(),
            force: core::array::from_fn(|a| axis(v.force[a], forces && a < d)),
            damping: core::array::from_fn(|k| axis(v.damping[k], per_particle)),
            affine: core::array::from_fn(|k| {
                axis(v.affine[k / 3][k % 3], apic && k / 3 < d && k % 3 < d)
            }),
            temperature: axis(v.temperature, heat),
            concentration: axis(v.concentration, diffusion),
            grid_temperature: axis(v.grid_temperature, heat),
            grid_concentration: axis(v.grid_concentration, diffusion),
            hoop: axis(v.hoop, axisymmetric),
            plastic: axis(v.plastic, def.effects.plasticity),
            temperature_source: axis(v.temperature_source, sources(def.effects.heat)),
            concentration_source: axis(v.concentration_source, sources(def.effects.diffusion)),
        };
        // SAFETY: checked non-NULL.
        unsafe { put(view_out, out) };
        Ok(())
    })
}

/// Copies `per` values of every particle, interleaved (particle-major), produced by `value(view,
/// particle, k)`, into `out` (`out_len` values), and the number written into `written_out`.
///
/// # Safety
/// `world` is NULL or a world; `out` is NULL or valid for `out_len` writes; `written_out` is
/// NULL or valid.
unsafe fn copy_out<T: Copy>(
    world: *const MpmWorld,
    out: *mut T,
    out_len: usize,
    written_out: *mut usize,
    per: impl Fn(usize) -> usize,
    value: impl Fn(&ParticlesView<'_>, usize, usize) -> T,
) -> MpmStatus {
    guard(|| {
        non_null(out)?;
        non_null(written_out)?;
        // SAFETY: the caller promises a world.
        let w: WorldRef<'_> = unsafe { world_ref(world) }?;
        let v = w.particles();
        let d = w.def().axes();
        let k = per(d);
        let n = v.count * k;
        if out_len < n {
            return Err(MpmStatus::OutputTooSmall);
        }
        apart(w.as_bytes(), out, n)?;
        apart(w.as_bytes(), written_out, 1)?;
        // SAFETY: non-NULL, the caller promises `out_len >= n` writable values, and they lie
        // outside the world's memory (checked).
        let dst = unsafe { core::slice::from_raw_parts_mut(out, n) };
        for i in 0..v.count {
            for j in 0..k {
                dst[i * k + j] = value(&v, i, j);
            }
        }
        // SAFETY: checked non-NULL.
        unsafe { put(written_out, n) };
        Ok(())
    })
}

/// Positions, interleaved: x, y (, z) per particle; `count * D` values.
///
/// # Safety
/// As the copy-out contract: `world` a world, `out` valid for `out_len` values, `written_out`
/// valid (NULL pointers are refused).
#[no_mangle]
pub unsafe extern "C" fn mpm_world_copy_positions(
    world: *const MpmWorld,
    out: *mut mpm_real,
    out_len: usize,
    written_out: *mut usize,
) -> MpmStatus {
    // SAFETY: forwarded contract.
    unsafe {
        copy_out(
            world,
            out,
            out_len,
            written_out,
            |d| d,
            |v, i, a| v.position[a][i],
        )
    }
}

/// Velocities, interleaved like positions; `count * D` values.
///
/// # Safety
/// As `mpm_world_copy_positions`.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_copy_velocities(
    world: *const MpmWorld,
    out: *mut mpm_real,
    out_len: usize,
    written_out: *mut usize,
) -> MpmStatus {
    // SAFETY: forwarded contract.
    unsafe {
        copy_out(
            world,
            out,
            out_len,
            written_out,
            |d| d,
            |v, i, a| v.velocity[a][i],
        )
    }
}

/// Stress (tau/rho0), interleaved per particle: 2D xx, yy, xy, zz (4 values); 3D xx, yy, zz,
/// xy, xz, yz (6 values).
///
/// # Safety
/// As `mpm_world_copy_positions`.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_copy_stress(
    world: *const MpmWorld,
    out: *mut mpm_real,
    out_len: usize,
    written_out: *mut usize,
) -> MpmStatus {
    let per = |d: usize| if d == 3 { 6 } else { 4 };
    // SAFETY: forwarded contract.
    unsafe {
        copy_out(world, out, out_len, written_out, per, |v, i, k| {
            v.stress[k][i]
        })
    }
}

/// J = det F of every particle (current over initial volume); `count` values.
///
/// # Safety
/// As `mpm_world_copy_positions`.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_copy_jacobians(
    world: *const MpmWorld,
    out: *mut mpm_real,
    out_len: usize,
    written_out: *mut usize,
) -> MpmStatus {
    // SAFETY: forwarded contract.
    unsafe {
        copy_out(
            world,
            out,
            out_len,
            written_out,
            |_| 1,
            |v, i, _| v.jacobian(i),
        )
    }
}

/// Statuses (`MpmParticleStatus`); `count` values.
///
/// # Safety
/// As `mpm_world_copy_positions`.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_copy_status(
    world: *const MpmWorld,
    out: *mut u32,
    out_len: usize,
    written_out: *mut usize,
) -> MpmStatus {
    // SAFETY: forwarded contract.
    unsafe {
        copy_out(
            world,
            out,
            out_len,
            written_out,
            |_| 1,
            |v, i, _| v.status[i],
        )
    }
}

/// Counts, time and the sums over the active particles.
///
/// # Safety
/// `world` is NULL or a world; `diagnostics_out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn mpm_world_diagnostics(
    world: *const MpmWorld,
    diagnostics_out: *mut MpmDiagnostics,
) -> MpmStatus {
    guard(|| {
        non_null(diagnostics_out)?;
        // SAFETY: the caller promises a world.
        let w = unsafe { world_ref(world) }?;
        apart(w.as_bytes(), diagnostics_out, 1)?;
        let s = w.diagnostics();
        let out = MpmDiagnostics {
            particle_count: w.particle_count(),
            time: w.time(),
            step_count: w.step_count(),
            mass: s.mass,
            momentum: s.momentum,
            angular_momentum: s.angular_momentum,
            center_of_mass: s.center_of_mass,
            kinetic: s.kinetic,
            strain: s.strain,
            potential: s.potential,
        };
        // SAFETY: checked non-NULL.
        unsafe { put(diagnostics_out, out) };
        Ok(())
    })
}
