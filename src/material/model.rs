//! The vocabulary every model speaks: the deformation it sees ([`Deformation`]), the stress it
//! gives ([`Stress`]), Lamé's constants ([`Lame`]) and the trait a model implements
//! ([`Model`]). The model files build on this alone; `material/mod.rs` maps a record to its
//! model and runs it.

use crate::layout::MaterialRecord;
use crate::num::{MatOf, Num};
use crate::Real;

/// Stress as a D x D matrix plus the plane-strain `zz` component (0 in 3D), of one particle
/// (`T = Real`) or of a vector of them ([`Wide`](crate::simd::wide::Wide)).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stress<const D: usize, T = Real> {
    pub m: MatOf<T, D>,
    pub zz: T,
}

impl<const D: usize> Stress<D> {
    /// The components in the stored order ([`crate::layout::sym_pairs`], then `zz` in 2D).
    #[inline(always)]
    pub fn stored(&self) -> [Real; 6] {
        let mut tau = [0.0; 6];
        for (k, &(a, b)) in crate::layout::sym_pairs(D).iter().enumerate() {
            tau[k] = self.m[a][b];
        }
        if D == 2 {
            tau[3] = self.zz;
        }
        tau
    }
}

/// The state a model sees: `H = F - I` in the plane of the D axes, the out-of-plane
/// `F_zz - 1` (2D only; ignored in 3D), `J - 1 = det F - 1` of the whole 3 x 3 `F`, and the
/// plastic history (0 for models without one), of one particle (`T = Real`) or of a vector of
/// them. For the inelastic models F is the elastic part `F_e`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Deformation<const D: usize, T = Real> {
    pub h: MatOf<T, D>,
    pub hzz: T,
    pub jm1: T,
    pub plastic: T,
}

impl<const D: usize, T: Num> Deformation<D, T> {
    /// From `H` and the out-of-plane `F_zz - 1` (0 in plane strain and in 3D), no history.
    #[inline(always)]
    pub fn new(h: MatOf<T, D>, hzz: T) -> Self {
        Self::with_plastic(h, hzz, T::splat(0.0))
    }

    /// From `H`, `F_zz - 1` and the plastic history.
    #[inline(always)]
    pub fn with_plastic(h: MatOf<T, D>, hzz: T, plastic: T) -> Self {
        let j2 = crate::math::det_identity_plus_minus_one(&h);
        let jm1 = if D == 2 { j2 + hzz + j2 * hzz } else { j2 };
        Deformation {
            h,
            hzz,
            jm1,
            plastic,
        }
    }
}

/// Lamé's lambda and mu (E33): all the elastic models (corotated linear, neo-Hookean,
/// fixed-corotated) read of a material record, and the Hencky elasticity (E37) of the plastic
/// models von Mises and Drucker-Prager.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lame {
    /// Lamé's lambda, Pa.
    pub lambda: Real,
    /// The shear modulus mu, Pa.
    pub mu: Real,
}

impl Lame {
    /// The Lamé constants of record `r`, as [`Model::params`] takes them.
    #[inline(always)]
    pub fn of(r: &MaterialRecord) -> Lame {
        Lame {
            lambda: r.lambda,
            mu: r.mu,
        }
    }
}

/// A constitutive model (E3, E33-E46): the deformation in, Kirchhoff stress out; an
/// inelastic model (a fluid, plasticity) also changes the deformation each step before its
/// stress is taken ([`Model::inelastic`]). Adding a model takes the four steps of the module's
/// "Adding a material"; the first is its own file implementing this trait.
pub(crate) trait Model {
    /// The parameters the model reads: its own fields of a material record, no more.
    type Params: Copy;

    /// The parameters of material `r`: copies of its fields (what is derived was derived once
    /// when the material was added, in [`material_record`](super::material_record)), so that a chunk's stress update
    /// pays nothing for fields its model does not read.
    fn params(r: &MaterialRecord) -> Self::Params;

    /// Whether [`Model::inelastic`] changes anything (false: the step skips it).
    const INELASTIC: bool = false;

    /// Whether, under an eigenstrain `d`, [`Model::inelastic`] acts on the elastic part
    /// `F / (1 + d)` (E47), which then takes the eigenstrain back: a return mapping, whose
    /// yield reads the elastic strain (a free expansion neither yields nor flows). False for a
    /// projection that keeps `J` (the fluid's), which acts on `F` itself: in plane strain the
    /// eigenstrain's out-of-plane part is not in the stored `F`, and the elastic part's
    /// projection would change the volume.
    const ON_ELASTIC_PART: bool = true;

    /// This step's inelastic part and the Kirchhoff stress of its result: the trial state
    /// (`F_e` updated by `dF`) in, the elastic state and history the stress is taken from out
    /// (a plastic return mapping; a fluid's projection to `J^(1/3) I`), with its stress. A
    /// return that works in the principal strains of the trial `F_e` (the plastic models)
    /// takes the stress from the same decomposition: one eigen decomposition a particle, not
    /// two. `hoop`: the out-of-plane stretch of a 2D deformation is free (axisymmetric), not
    /// held at 1 (plane strain). Written on [`Num`] without branches, as [`Model::kirchhoff`].
    /// By default nothing is inelastic.
    #[inline(always)]
    fn inelastic<const D: usize, T: Num>(
        p: &Self::Params,
        f: &Deformation<D, T>,
        _hoop: bool,
    ) -> (Deformation<D, T>, Stress<D, T>) {
        (*f, Self::kirchhoff(p, f))
    }

    /// The Kirchhoff stress `tau` (not yet divided by `rho0`) for `jm1 = det F - 1 > -1`,
    /// written once on [`Num`]: of one particle (`T = Real`, the reference step) or of the
    /// lanes of one of the instance's vectors (`T = Wide<I>`, a chunk's update). Lanes not
    /// updated may hold any value; their results are not used.
    fn kirchhoff<const D: usize, T: Num>(p: &Self::Params, f: &Deformation<D, T>) -> Stress<D, T>;

    /// Whether a chunk's update runs the model on the instance's vectors ([`Wide`](crate::simd::wide::Wide)) in `D`
    /// dimensions, rather than lane by lane on [`Real`] in a loop the compiler vectorises.
    /// Lane by lane is the faster form for a formula without loops or calls; an iteration
    /// whose count differs by particle (a polar decomposition) vectorises only on vectors.
    #[inline(always)]
    fn on_vectors(_d: usize) -> bool {
        false
    }

    /// Strain energy per unit initial volume, J/m^3 (energy checks and diagnostics).
    fn energy<const D: usize>(p: &Self::Params, f: &Deformation<D>) -> Real;

    /// Whether `plastic` is a plastic history this model can leave (what [`World::open`]
    /// checks a snapshot against): 0 for a model without one, which never changes it.
    ///
    /// [`World::open`]: crate::World::open
    fn history_in_range(plastic: Real) -> bool {
        plastic == 0.0
    }

    /// Whether the wave speed of material `r` changes with the plastic history, so that a
    /// substep chosen for it can be outgrown within a step.
    fn hardens(_r: &MaterialRecord) -> bool {
        false
    }

    /// The volume ratio `J - 1` of a particle (current volume over initial, less 1) from the
    /// `J - 1` of its stored deformation and its plastic history: the stored one unless the
    /// model keeps part of the volume change in its history.
    fn volume_ratio_minus_one(jm1: Real, _plastic: Real) -> Real {
        jm1
    }

    /// The dilatational wave speed of a particle of material `r` with plastic history
    /// `plastic`, m/s, in f64: what the stable step resolves (E86, E88). The material's own unless
    /// the model [hardens](Model::hardens); then it must not grow with the history: the stable
    /// step takes a material's least history (of its active particles) for its fastest.
    fn wave_speed(r: &MaterialRecord, _plastic: Real) -> f64 {
        r.wave_speed as f64
    }
}
