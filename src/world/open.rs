//! Opening a world from bytes another call, process or machine wrote: [`WorldRef::open`]'s
//! checks of the header, the tables and every particle's state, which [`World::open`] runs
//! too, so that a snapshot no call of this API could have written is refused.

use super::{check_buffer, World, WorldRef};
use crate::layout::{col, ColliderImpulse, ColliderRecord};
use crate::material::{material_record, material_resolvable, model_of};
use crate::{Error, Real};
use core::mem::size_of;

impl<'a> WorldRef<'a> {
    /// Reads the world that `buf` holds, with the checks of [`World::open`] (the state
    /// included).
    pub fn open(buf: &'a [u8]) -> Result<WorldRef<'a>, Error> {
        let w = WorldRef::reopen(buf)?;
        w.check_state()?;
        Ok(w)
    }

    /// Reads the world that `buf` holds, with the constant-time checks of [`World::reopen`].
    pub fn reopen(buf: &'a [u8]) -> Result<WorldRef<'a>, Error> {
        let total = World::stored_bytes(buf)?;
        check_buffer(buf, total)?;
        Ok(WorldRef { buf })
    }

    /// Checks the state of a world whose header is sound, as [`World::open`] does; the first
    /// problem found is [`Error::InvalidState`]. What holds in every world this API produced:
    /// - the time is finite and >= 0; the thermostat's alpha finite, in `[0, max_alpha]`
    ///   (0 without one); the smallest particle mass is the smallest of the particles' masses
    ///   (infinite before the first particle);
    /// - each material record is what [`World::add_material`] makes of a valid definition;
    ///   each traction names an existing particle and a face of the dimension, with a finite
    ///   traction; each collider is one [`World::add_collider`] could have written and the
    ///   steps moved on, posed at the world's time (its values within [`Real`], as
    ///   `add_collider` checks a definition);
    /// - every particle has a known status and material, a finite mass and volume > 0, a
    ///   position in the admissible region (the grid less the shape function's margin; on
    ///   its wall planes, where the step puts a particle that reaches them), and every value
    ///   it carries is finite (velocity, `H` with `J > 0`, stress, and the columns of its
    ///   declared effects: forces, damping >= 0, moment matrix, transported values and
    ///   sources, hoop stretch > -1): a particle frozen or escaped in a step keeps its last
    ///   finite state.
    pub fn check_state(&self) -> Result<(), Error> {
        let invalid = Err(Error::InvalidState);
        let h = self.header();
        let def = self.def();
        let layout = self.layout();
        let d = layout.d;
        let n = self.particle_count();
        let max_alpha = def
            .effects
            .damping
            .and_then(|dm| dm.feedback)
            .map_or(0.0, |f| f.max_alpha as f64);
        let alpha_ok = (0.0..=max_alpha).contains(&h.feedback_alpha);
        if !(h.time.is_finite() && h.time >= 0.0 && alpha_ok) {
            return invalid;
        }
        for (id, rec) in self.materials().iter().enumerate() {
            let again = self.material(id as u32).map(|m| material_record(&m));
            if !matches!(again, Some(Ok(r)) if bytemuck::bytes_of(&r) == bytemuck::bytes_of(rec)) {
                return invalid;
            }
            if model_of(rec).plastic() && !def.effects.plasticity {
                return invalid;
            }
            if !material_resolvable(rec, &def) {
                return invalid;
            }
        }
        if !self.traction_records().iter().all(|t| t.is_valid(n, d)) {
            return invalid;
        }
        let colliders = h.collider_count as usize;
        if h.collider_count > h.collider_capacity || h.sdf_count > h.sdf_capacity {
            return invalid;
        }
        let at = layout.colliders_offset;
        let records: &[ColliderRecord] =
            bytemuck::cast_slice(&self.buf[at..at + colliders * size_of::<ColliderRecord>()]);
        let at = layout.impulses_offset;
        let impulses: &[ColliderImpulse] =
            bytemuck::cast_slice(&self.buf[at..at + colliders * size_of::<ColliderImpulse>()]);
        let finite = |i: &ColliderImpulse| {
            (i.linear.iter().chain(&i.angular).chain(&i.taken)).all(|c| c.is_finite())
                && i.duration >= 0.0
        };
        let valid = |r: &ColliderRecord| r.is_valid(h.sdf_count, h.planar(), h.time);
        if !records.iter().all(valid) || !impulses.iter().all(finite) {
            return invalid;
        }
        let at = layout.sdf_offset;
        let samples: &[Real] =
            bytemuck::cast_slice(&self.buf[at..at + h.sdf_count as usize * size_of::<Real>()]);
        if !samples.iter().all(|d| d.is_finite()) {
            return invalid;
        }
        // Every particle as the state setters check the values they would leave
        // (`ParticleRules::check`); the MUSL start positions and the cpGIMP stretches are
        // scratch, which every substep writes before it reads them.
        let rules = super::state::ParticleRules::new(self);
        let mut columns: [&[Real]; super::state::MAX_COLUMNS] = [&[]; super::state::MAX_COLUMNS];
        for (j, c) in columns
            .iter_mut()
            .enumerate()
            .take(layout.particle_real_columns)
        {
            *c = self.real_col(&layout, j, n);
        }
        let material = self.u32_col(&layout, col::MATERIAL, n);
        let status = self.u32_col(&layout, col::STATUS, n);
        let mut min_mass = f64::INFINITY;
        for i in 0..n {
            min_mass = min_mass.min(columns[col::mass(d)][i] as f64);
            let value = |j: usize| columns[j].get(i).copied().unwrap_or(Real::NAN);
            if rules.check(value, material[i], status[i]).is_err() {
                return invalid;
            }
        }
        if h.min_particle_mass != min_mass {
            return invalid;
        }
        Ok(())
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;
    use crate::def::WorldDef;
    use crate::layout::{Header, Layout, MaterialRecord, TractionRecord};
    use crate::{HeapBuffer, MaterialDef, Vec3};

    /// A world of `def` in `mem` with one block of the default material, 0.4 m to 0.8 m.
    fn block_world<'a>(def: &WorldDef, mem: &'a mut [u8]) -> World<'a> {
        let mut w = World::init(def, mem).unwrap();
        let m = w.add_material(&MaterialDef::DEFAULT).unwrap();
        let (lo, hi) = (Vec3::new(0.4, 0.4, 0.0), Vec3::new(0.8, 0.8, 0.0));
        w.fill_box(lo, hi, m, Vec3::ZERO).unwrap();
        w
    }

    /// `open` checks the header's state and the tables as well as the particles: each edit
    /// of a snapshot that no call produces is `InvalidState` (a particle count raised over
    /// empty slots, a time, minimum mass or thermostat alpha out of range, a material record
    /// that is not what `add_material` makes of its definition, a traction naming no particle
    /// or face, or not finite), and the bytes stay as they were; the intact snapshot opens.
    #[cfg(feature = "effects")]
    #[test]
    fn open_refuses_damaged_header_state_and_tables() {
        use crate::{Damping, Effects, Face, Feedback, Schedule};
        let def = WorldDef {
            cells: [16, 16, 1],
            cell_size: 0.1,
            particle_capacity: 512,
            effects: Effects {
                damping: Some(Damping {
                    feedback: Some(Feedback {
                        gain: 1.0,
                        target: Schedule::ZERO,
                        max_alpha: 10.0,
                    }),
                    ..Damping::NONE
                }),
                traction_capacity: 8,
                ..Effects::NONE
            },
            ..WorldDef::DEFAULT
        };
        let layout = Layout::of(&def);
        let mut buf = HeapBuffer::new(crate::memory_requirements(&def).unwrap().bytes);
        let mut w = block_world(&def, buf.as_mut_bytes());
        w.add_tractions(0..2, Face::XMax, Vec3::new(1.0, 0.0, 0.0))
            .unwrap();
        let snapshot = w.as_bytes().to_vec();
        type Edit = fn(&mut Header, &mut MaterialRecord, &mut TractionRecord);
        let edits: [(&str, Edit); 18] = [
            ("count over empty slots", |h, _, _| h.particle_count += 30),
            ("time NaN", |h, _, _| h.time = f64::NAN),
            ("time negative", |h, _, _| h.time = -1.0),
            ("min mass NaN", |h, _, _| h.min_particle_mass = f64::NAN),
            ("min mass negative", |h, _, _| h.min_particle_mass = -1.0),
            ("min mass not the least", |h, _, _| {
                h.min_particle_mass *= 0.5
            }),
            ("alpha NaN", |h, _, _| h.feedback_alpha = f64::NAN),
            ("alpha negative", |h, _, _| h.feedback_alpha = -1.0),
            ("alpha over its bound", |h, _, _| h.feedback_alpha = 11.0),
            ("modulus NaN", |_, r, _| r.youngs_modulus = Real::NAN),
            ("Lame parameter edited", |_, r, _| r.lambda *= 2.0),
            ("unknown model", |_, r, _| r.model = 7.0),
            ("traction of no particle", |_, _, t| t.particle = 999),
            ("traction normal off the plane", |_, _, t| t.normal[2] = 1.0),
            ("traction normal not unit", |_, _, t| t.normal[0] = 2.0),
            ("traction area zero", |_, _, t| t.traction[3] = 0.0),
            ("traction schedule past the table", |_, _, t| t.schedule = 4),
            ("traction NaN", |_, _, t| t.traction[1] = Real::NAN),
        ];
        let mut copy = HeapBuffer::new(snapshot.len());
        for (what, edit) in edits {
            let mem = copy.as_mut_bytes();
            mem.copy_from_slice(&snapshot);
            let (head, rest) = mem.split_at_mut(layout.materials_offset);
            let h: &mut Header = bytemuck::from_bytes_mut(&mut head[..size_of::<Header>()]);
            let (mat, rest) = rest.split_at_mut(size_of::<MaterialRecord>());
            let r: &mut MaterialRecord = bytemuck::from_bytes_mut(mat);
            let at =
                layout.tractions_offset - layout.materials_offset - size_of::<MaterialRecord>();
            let t: &mut TractionRecord =
                bytemuck::from_bytes_mut(&mut rest[at..at + size_of::<TractionRecord>()]);
            edit(h, r, t);
            let before = mem.to_vec();
            assert_eq!(World::open(mem).err(), Some(Error::InvalidState), "{what}");
            assert!(
                *mem == before[..],
                "{what}: the refused open changed the bytes"
            );
        }
        copy.as_mut_bytes().copy_from_slice(&snapshot);
        assert!(World::open(copy.as_mut_bytes()).is_ok());
    }

    /// `open` checks a collider record as `add_collider` checks a definition: each edit of a
    /// snapshot's record that `add_collider` could not have written, nor a step since, is
    /// `InvalidState`, the bytes unchanged. Values past `Real`'s range (which read back as
    /// infinities, and a collider so placed touched nothing), not finite, or not what the
    /// definition's check admits (a length of zero or one rounding to zero in `Real`, a
    /// negative friction, a rotation not of unit length, unknown numbers), what `add_collider`
    /// stores of no definition (a sphere's unused lengths, a distance field's numbers on
    /// another shape, a field past the samples), a pose time other than the world's, and in
    /// 2D a z component or a turn not about z. The intact snapshot opens, in 2D and 3D (where
    /// z is read).
    #[cfg(feature = "effects")]
    #[test]
    fn open_refuses_collider_records_add_collider_could_not_write() {
        use crate::{ColliderDef, ColliderShape, Contact, Dimension, Effects};
        use std::{vec, vec::Vec};
        type Edit = fn(&mut ColliderRecord, f64);
        // Past the largest Real: infinite in Real (f32), or in f64 itself.
        const BEYOND: f64 = Real::MAX as f64 * 2.0;
        // A length that rounds to zero in f32 (positive in f64, where no edit is needed).
        let rounds_to_zero = 1.0e-300;
        let mut edits: Vec<(&str, Edit)> = vec![
            ("position x past Real", |r, _| r.position[0] = BEYOND),
            ("position y NaN", |r, _| r.position[1] = f64::NAN),
            ("position x infinite", |r, _| r.position[0] = f64::INFINITY),
            ("velocity x past Real", |r, _| r.velocity[0] = BEYOND),
            ("velocity y NaN", |r, _| r.velocity[1] = f64::NAN),
            ("angular velocity z past Real", |r, _| {
                r.angular_velocity[2] = BEYOND
            }),
            ("radius past Real", |r, _| r.size[0] = BEYOND),
            ("radius zero", |r, _| r.size[0] = 0.0),
            ("radius negative", |r, _| r.size[0] = -0.1),
            ("a sphere's second length", |r, _| r.size[1] = 0.5),
            ("friction past Real", |r, _| r.friction = BEYOND),
            ("friction negative", |r, _| r.friction = -0.25),
            ("friction NaN", |r, _| r.friction = f64::NAN),
            ("rotation zero", |r, _| r.rotation = [0.0; 4]),
            ("rotation of length 2", |r, _| {
                r.rotation = [0.0, 0.0, 0.0, 2.0]
            }),
            ("rotation NaN", |r, _| r.rotation[3] = f64::NAN),
            ("pose time NaN", |r, _| r.pose_time = f64::NAN),
            ("pose time infinite", |r, _| r.pose_time = f64::INFINITY),
            ("pose time after the world's", |r, t| r.pose_time = t + 1.0),
            ("pose time before the world's", |r, t| r.pose_time = t - 1.0),
            ("pose time far before the world's", |r, _| {
                r.pose_time = -1.0e300
            }),
            ("unknown contact", |r, _| r.contact = 3),
            ("unknown shape", |r, _| r.shape = 9),
            ("a distance field's numbers on a sphere", |r, _| {
                r.grid[1] = 2
            }),
            ("2D: position z", |r, _| r.position[2] = 0.5),
            ("2D: velocity z", |r, _| r.velocity[2] = 1.0),
            ("2D: a turn about x", |r, _| r.angular_velocity[0] = 1.0),
        ];
        if rounds_to_zero as Real == 0.0 {
            edits.push(("radius rounding to zero", |r, _| r.size[0] = 1.0e-300));
            edits.push(("friction not a Real", |r, _| r.friction = 0.1));
        }
        let mut def = WorldDef {
            cells: [16, 16, 1],
            cell_size: 0.1,
            particle_capacity: 512,
            effects: Effects {
                collider_capacity: 2,
                sdf_capacity: 8,
                ..Effects::NONE
            },
            ..WorldDef::DEFAULT
        };
        let sphere = ColliderDef {
            shape: ColliderShape::Sphere { radius: 0.2 },
            position: Vec3::new(0.8, 0.5, 0.0),
            velocity: Vec3::new(0.5, 0.0, 0.0),
            angular_velocity: Vec3::new(0.0, 0.0, 2.0),
            contact: Contact::Slip,
            friction: 0.25,
            ..ColliderDef::DEFAULT
        };
        let field = ColliderDef {
            shape: ColliderShape::Sdf {
                first: 0,
                dims: [2, 2, 2],
                spacing: 0.5,
            },
            ..ColliderDef::DEFAULT
        };
        for dimension in [Dimension::Plane2D, Dimension::ThreeD] {
            def.dimension = dimension;
            def.cells[2] = if dimension == Dimension::ThreeD {
                16
            } else {
                1
            };
            let layout = Layout::of(&def);
            let mut buf = HeapBuffer::new(crate::memory_requirements(&def).unwrap().bytes);
            let mut w = block_world(&def, buf.as_mut_bytes());
            let dims_z = if dimension == Dimension::ThreeD { 2 } else { 1 };
            w.add_distance_field(&[1.0; 8]).unwrap();
            w.add_collider(&ColliderDef {
                position: Vec3::new(0.8, 0.5, 0.75),
                ..sphere
            })
            .unwrap();
            let dims = [2, 2, dims_z];
            w.add_collider(&ColliderDef {
                shape: ColliderShape::Sdf {
                    first: 8 - 4 * dims_z,
                    dims,
                    spacing: 0.5,
                },
                ..field
            })
            .unwrap();
            // Moved on by steps: positions and rotations are the steps' f64 arithmetic.
            for _ in 0..3 {
                w.step(1.0e-3).unwrap();
            }
            let time = w.time();
            let snapshot = w.as_bytes().to_vec();
            let mut copy = HeapBuffer::new(snapshot.len());
            let record = |k: usize| {
                let at = layout.colliders_offset + k * size_of::<ColliderRecord>();
                at..at + size_of::<ColliderRecord>()
            };
            let field_edits: [(&str, Edit); 3] = [
                ("a field past the samples", |r, _| r.grid[0] = 5),
                ("a field of one sample along x", |r, _| r.grid[1] = 1),
                ("a field's count overflowing", |r, _| {
                    r.grid = [0, u64::MAX, 2, 2]
                }),
            ];
            let planar = dimension != Dimension::ThreeD;
            let cases = edits
                .iter()
                .filter(|(what, _)| planar || !what.starts_with("2D"))
                .map(|e| (0, e))
                .chain(field_edits.iter().map(|e| (1, e)));
            for (k, (what, edit)) in cases {
                let mem = copy.as_mut_bytes();
                mem.copy_from_slice(&snapshot);
                edit(bytemuck::from_bytes_mut(&mut mem[record(k)]), time);
                let before = mem.to_vec();
                assert_eq!(
                    World::open(mem).err(),
                    Some(Error::InvalidState),
                    "{dimension:?}: {what}"
                );
                assert!(
                    *mem == before[..],
                    "{what}: the refused open changed the bytes"
                );
            }
            copy.as_mut_bytes().copy_from_slice(&snapshot);
            let opened = World::open(copy.as_mut_bytes()).expect("the intact snapshot opens");
            let z = opened.collider(0).unwrap().def.position.z;
            assert_eq!(z, if planar { 0.0 } else { 0.75 }, "{dimension:?}");
        }
    }

    /// The step count saturates: a world at `u64::MAX` steps stays there after another step
    /// (a snapshot may carry any count).
    #[test]
    fn step_count_does_not_wrap() {
        let def = WorldDef {
            cells: [16, 16, 1],
            cell_size: 0.1,
            particle_capacity: 256,
            ..WorldDef::DEFAULT
        };
        let mut buf = HeapBuffer::new(crate::memory_requirements(&def).unwrap().bytes);
        let mut w = block_world(&def, buf.as_mut_bytes());
        w.header_mut().step_count = u64::MAX;
        w.step(1.0e-3).unwrap();
        assert_eq!(w.step_count(), u64::MAX);
    }
}
