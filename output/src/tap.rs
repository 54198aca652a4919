//! A source and a sink, the host's side of material that comes and goes: a [`Tap`] adds a
//! stream of particles at a steady rate and removes whatever reaches its drain, once a frame,
//! between steps. The kernel keeps no emitter of its own: it adds particles
//! ([`World::add_particles`]) and removes them ([`World::remove_particles`] with
//! [`Removal::Box`]), and the removal frees the room the stream fills again, so a tap pours
//! for as long as the host runs it with the particle count bounded by the stream's rate times
//! the time a particle takes to reach the drain.

use mpm_gimp::{Error, ParticleBatch, Real, Removal, Vec3, World};

/// A stream of particles leaving a nozzle, and a drain box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tap {
    /// Centre of the nozzle's mouth, m: the stream leaves it along -y. The rows a frame adds
    /// start in the nozzle above it, up to `speed` times the frame's length (the world must
    /// admit them there).
    pub nozzle: Vec3,
    /// Width of the stream across x, m (2D: the stream is a sheet in plane strain).
    pub width: Real,
    /// Speed of the stream along -y, m/s (> 0).
    pub speed: Real,
    /// Material of the stream, an id the world gave.
    pub material: u32,
    /// Density of that material, kg/m^3: each particle's mass is `density * spacing^2`.
    pub density: Real,
    /// Spacing of the stream's particles across and along it, m: the world's cell size over
    /// its particles per cell, as a fill places them.
    pub spacing: Real,
    /// The drain: every particle inside this box (lowest corner, highest corner) is removed.
    pub drain: (Vec3, Vec3),
}

impl Tap {
    /// Before the frame that takes the world from its time `t` to `t + dt`: removes what the
    /// drain holds, then adds the rows the stream delivers in the frame: row `k` leaves the
    /// nozzle at `t_k = k spacing / speed`, for every `t < t_k <= t + dt` (a function of the
    /// world's time: the tap keeps no state, and a snapshot resumes it). Each row is placed
    /// where the stream has it at `t`: `speed (t_k - t)` above the mouth, moving at `speed`,
    /// so that the step brings it out at `t_k` and the rows of one frame join the last
    /// frame's at the stream's spacing (placed at the mouth at once, a frame's rows left a gap
    /// or an overlap behind the last frame's, and the stream fell as a dotted line). Adds the
    /// rows that fit in the room left and skips the rest (a full world pours less). Returns
    /// how many particles it removed and added.
    pub fn frame(&self, world: &mut World, dt: Real) -> Result<(usize, usize), Error> {
        let removed = world.remove_particles(Removal::Box {
            min: self.drain.0,
            max: self.drain.1,
        })?;
        let t = world.time();
        let (speed, spacing) = (self.speed as f64, self.spacing as f64);
        let rows_by = |t: f64| (speed * t / spacing).floor() as i64;
        let first = rows_by(t) + 1;
        let rows = (rows_by(t + dt as f64) - rows_by(t)).max(0) as usize;
        let across = ((self.width / self.spacing).round() as usize).max(1);
        let room = world.def().particle_capacity as usize - world.particle_count();
        let rows = rows.min(room / across);
        let n = rows * across;
        let mut x = Vec::with_capacity(n);
        let mut y = Vec::with_capacity(n);
        for row in 0..rows {
            // Row `first + row` leaves the mouth `t_k - t` into the frame.
            let t_k = (first + row as i64) as f64 * spacing / speed;
            let above = (speed * (t_k - t)) as Real;
            for k in 0..across {
                let offset = (k as Real + 0.5 - 0.5 * across as Real) * self.spacing;
                x.push(self.nozzle.x + offset);
                y.push(self.nozzle.y + above);
            }
        }
        let vy = vec![-self.speed; n];
        let zero = vec![0.0; n];
        let volume = self.spacing * self.spacing;
        world.add_particles(&ParticleBatch {
            position: [&x, &y, &[]],
            velocity: [&zero, &vy, &[]],
            mass: &vec![self.density * volume; n],
            volume: &vec![volume; n],
            material: &vec![self.material; n],
        })?;
        Ok((removed, n))
    }
}
