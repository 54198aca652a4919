//! A material's record ([`MaterialRecord`], what the world stores): its definition checked,
//! and what the step derives from it once (Lame parameters, wave speed, the plastic models'
//! constants).

use crate::def::{MaterialDef, WorldDef};
use crate::layout::MaterialRecord;
use crate::{Error, Real};

/// The record of a valid material definition, with what the step derives from it (Lame
/// parameters, wave speed), or `InvalidMaterial`.
pub(crate) fn material_record(m: &MaterialDef) -> Result<MaterialRecord, Error> {
    let ok = m.youngs_modulus.is_finite()
        && m.youngs_modulus > 0.0
        && m.poisson_ratio > -1.0
        && m.poisson_ratio < 0.5
        && m.density.is_finite()
        && m.density > 0.0
        && m.heat_capacity.is_finite()
        && m.heat_capacity > 0.0
        && m.conductivity.is_finite()
        && m.conductivity >= 0.0
        && m.diffusivity.is_finite()
        && m.diffusivity >= 0.0
        && m.thermal_expansion.is_finite()
        && m.reference_temperature.is_finite()
        && m.swelling.is_finite()
        && m.reference_concentration.is_finite()
        && m.viscosity.is_finite()
        && m.viscosity >= 0.0
        && m.bulk_viscosity.is_finite()
        && m.bulk_viscosity >= 0.0
        && m.volume_relaxation.is_finite()
        && m.volume_relaxation >= 0.0
        && m.bulk_modulus.is_finite()
        && m.bulk_modulus > 0.0
        && m.pressure_exponent.is_finite()
        && m.pressure_exponent >= 1.0
        && m.yield_stress.is_finite()
        && m.yield_stress > 0.0
        && m.hardening_modulus.is_finite()
        && m.hardening_modulus >= 0.0
        && m.friction_angle >= 0.0
        && m.friction_angle < 90.0
        && m.cohesion.is_finite()
        && m.cohesion >= 0.0
        // The apex of the yield surface is at the tension c cot(phi).
        && (m.cohesion == 0.0 || m.friction_angle > 0.0)
        && m.critical_compression > 0.0
        && m.critical_compression < 1.0
        && m.critical_stretch.is_finite()
        && m.critical_stretch > 0.0
        && m.hardening_coefficient.is_finite()
        && m.hardening_coefficient >= 0.0
        && m.hardening_coefficient <= crate::MAX_HARDENING_COEFFICIENT;
    if !ok {
        return Err(Error::InvalidMaterial);
    }
    let (lambda, mu) = m.lame();
    let c = m.wave_speed();
    if !(lambda.is_finite() && mu.is_finite() && c.is_finite()) {
        return Err(Error::InvalidMaterial);
    }
    Ok(MaterialRecord {
        model: m.model as u32 as Real,
        youngs_modulus: m.youngs_modulus,
        poisson_ratio: m.poisson_ratio,
        density: m.density,
        lambda,
        mu,
        wave_speed: c,
        heat_capacity: m.heat_capacity,
        conductivity: m.conductivity,
        diffusivity: m.diffusivity,
        thermal_expansion: m.thermal_expansion,
        reference_temperature: m.reference_temperature,
        swelling: m.swelling,
        reference_concentration: m.reference_concentration,
        viscosity: m.viscosity,
        bulk_viscosity: m.bulk_viscosity,
        volume_relaxation: m.volume_relaxation,
        bulk_modulus: m.bulk_modulus,
        pressure_exponent: m.pressure_exponent,
        yield_stress: m.yield_stress,
        hardening_modulus: m.hardening_modulus,
        friction_angle: m.friction_angle,
        friction_fit: m.friction_fit as u32 as Real,
        cohesion: m.cohesion,
        critical_compression: m.critical_compression,
        critical_stretch: m.critical_stretch,
        hardening_coefficient: m.hardening_coefficient,
        friction_coefficient: m
            .friction_fit
            .alpha(m.friction_angle as f64 * core::f64::consts::PI / 180.0)
            as Real,
        apex_tension: apex_tension(m.friction_angle, m.cohesion),
        log_compression: libm::log1p(-(m.critical_compression as f64)) as Real,
        log_stretch: libm::log1p(m.critical_stretch as f64) as Real,
    })
}

/// The largest diffusivity of material `rec` that a step of a world of `def` integrates
/// explicitly, m^2/s: its thermal diffusivity `k / (rho C_p)` with heat conduction declared,
/// its diffusivity D with diffusion declared, and its kinematic viscosities' sum `(eta + zeta)
/// / rho0` (viscosity diffuses momentum; E87); the stable step keeps `dt <= h^2 / (2 d
/// kappa)` (E88).
pub(crate) fn explicit_diffusivity(rec: &MaterialRecord, def: &WorldDef) -> f64 {
    let fx = &def.effects;
    let rho = rec.density as f64;
    let thermal = if fx.heat.is_some() {
        rec.conductivity as f64 / (rho * rec.heat_capacity as f64)
    } else {
        0.0
    };
    let solvent = if fx.diffusion.is_some() {
        rec.diffusivity as f64
    } else {
        0.0
    };
    let viscous = (rec.viscosity as f64 + rec.bulk_viscosity as f64) / rho;
    thermal.max(solvent).max(viscous)
}

/// Whether a world of `def` resolves material `rec` in a stable step of at least
/// [`crate::MIN_STABLE_DT`]: its wave speed (unhardened) and its diffusivities
/// ([`crate::Resolvable`]).
pub(crate) fn material_resolvable(rec: &MaterialRecord, def: &WorldDef) -> bool {
    let limits = def.resolvable();
    rec.wave_speed as f64 <= limits.speed && explicit_diffusivity(rec, def) <= limits.diffusivity
}

/// The mean tension `c cot(phi)` the Drucker-Prager cone's apex sits at, Pa (0 without a
/// cohesion; E40).
fn apex_tension(degrees: Real, cohesion: Real) -> Real {
    if cohesion > 0.0 {
        let phi = degrees as f64 * core::f64::consts::PI / 180.0;
        (cohesion as f64 * libm::cos(phi) / libm::sin(phi)) as Real
    } else {
        0.0
    }
}
