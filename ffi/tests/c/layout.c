/*
 * Layout of every type of mpm_gimp.h as this compiler sees it: one line per type (size and
 * alignment) and one per struct field (offset and size). tests/c_checks.rs compares the lines
 * with the Rust definitions and checks that they cover every struct and field of the header.
 *
 * The same file compiles as C99 and as C++17. Alignment comes from offsetof on a probe struct
 * (a char, then the type), which C99 allows; C++ also checks the probe against alignof.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "mpm_gimp.h"

/* A struct whose second member sits at the alignment of T. */
#define PROBE(T) \
    struct probe_##T { \
        char c; \
        T t; \
    };

PROBE(mpm_real)
PROBE(size_t)
PROBE(MpmStatus)
PROBE(MpmDimension)
PROBE(MpmShape)
PROBE(MpmUpdateOrder)
PROBE(MpmTransfer)
PROBE(MpmBoundary)
PROBE(MpmFace)
PROBE(MpmMaterialModel)
PROBE(MpmFrictionFit)
PROBE(MpmParticleStatus)
PROBE(MpmScalarBoundaryKind)
PROBE(MpmScalarField)
PROBE(MpmColliderShape)
PROBE(MpmContact)
PROBE(MpmVec3)
PROBE(MpmSchedule)
PROBE(MpmFeedback)
PROBE(MpmDamping)
PROBE(MpmDampingZone)
PROBE(MpmScalarBoundary)
PROBE(MpmTransport)
PROBE(MpmEffects)
PROBE(MpmWorldDef)
PROBE(MpmMaterialDef)
PROBE(MpmParticlesView)
PROBE(MpmDiagnostics)
PROBE(MpmMemoryRequirements)
PROBE(MpmParticleArrays)
PROBE(MpmParticleState)
PROBE(MpmIdRange)
PROBE(MpmStepReport)
PROBE(MpmTaskSystem)
PROBE(MpmColliderDef)
PROBE(MpmColliderState)

#define ALIGN_OF(T) offsetof(struct probe_##T, t)

#ifdef __cplusplus
#define CHECK_PROBE(T) static_assert(ALIGN_OF(T) == alignof(T), "probe alignment of " #T);
#else
#define CHECK_PROBE(T)
#endif

#define TYPE(T) \
    do { \
        CHECK_PROBE(T) \
        printf("type %s size %lu align %lu\n", #T, (unsigned long)sizeof(T), \
               (unsigned long)ALIGN_OF(T)); \
    } while (0)

/* sizeof does not evaluate its operand: the null pointer is never dereferenced. */
#define FIELD(T, f) \
    printf("field %s.%s offset %lu size %lu\n", #T, #f, (unsigned long)offsetof(T, f), \
           (unsigned long)sizeof(((T *)0)->f))

int main(void) {
    TYPE(mpm_real);
    TYPE(size_t);

    TYPE(MpmStatus);
    TYPE(MpmDimension);
    TYPE(MpmShape);
    TYPE(MpmUpdateOrder);
    TYPE(MpmTransfer);
    TYPE(MpmBoundary);
    TYPE(MpmFace);
    TYPE(MpmMaterialModel);
    TYPE(MpmFrictionFit);
    TYPE(MpmParticleStatus);
    TYPE(MpmScalarBoundaryKind);
    TYPE(MpmScalarField);
    TYPE(MpmColliderShape);
    TYPE(MpmContact);

    TYPE(MpmVec3);
    FIELD(MpmVec3, x);
    FIELD(MpmVec3, y);
    FIELD(MpmVec3, z);

    TYPE(MpmSchedule);
    FIELD(MpmSchedule, points);
    FIELD(MpmSchedule, times);
    FIELD(MpmSchedule, values);

    TYPE(MpmFeedback);
    FIELD(MpmFeedback, declared);
    FIELD(MpmFeedback, gain);
    FIELD(MpmFeedback, target);
    FIELD(MpmFeedback, max_alpha);

    TYPE(MpmDamping);
    FIELD(MpmDamping, declared);
    FIELD(MpmDamping, grid);
    FIELD(MpmDamping, particle);
    FIELD(MpmDamping, feedback);
    FIELD(MpmDamping, per_particle);
    FIELD(MpmDamping, grid_on_force);
    FIELD(MpmDamping, zone_count);
    FIELD(MpmDamping, zones);

    TYPE(MpmDampingZone);
    FIELD(MpmDampingZone, min);
    FIELD(MpmDampingZone, max);
    FIELD(MpmDampingZone, rate);
    FIELD(MpmDampingZone, ramped);
    FIELD(MpmDampingZone, ramp_face);

    TYPE(MpmScalarBoundary);
    FIELD(MpmScalarBoundary, kind);
    FIELD(MpmScalarBoundary, value);

    TYPE(MpmTransport);
    FIELD(MpmTransport, declared);
    FIELD(MpmTransport, faces);
    FIELD(MpmTransport, sources);

    TYPE(MpmEffects);
    FIELD(MpmEffects, damping);
    FIELD(MpmEffects, particle_forces);
    FIELD(MpmEffects, traction_capacity);
    FIELD(MpmEffects, body_force);
    FIELD(MpmEffects, body_force_scale);
    FIELD(MpmEffects, body_force_gradient);
    FIELD(MpmEffects, traction_schedules);
    FIELD(MpmEffects, heat);
    FIELD(MpmEffects, diffusion);
    FIELD(MpmEffects, plasticity);
    FIELD(MpmEffects, collider_capacity);
    FIELD(MpmEffects, sdf_capacity);

    TYPE(MpmWorldDef);
    FIELD(MpmWorldDef, dimension);
    FIELD(MpmWorldDef, origin);
    FIELD(MpmWorldDef, cell_size);
    FIELD(MpmWorldDef, cells);
    FIELD(MpmWorldDef, particle_capacity);
    FIELD(MpmWorldDef, material_capacity);
    FIELD(MpmWorldDef, shape);
    FIELD(MpmWorldDef, particles_per_cell);
    FIELD(MpmWorldDef, flip_beta);
    FIELD(MpmWorldDef, pic_rate);
    FIELD(MpmWorldDef, transfer);
    FIELD(MpmWorldDef, update_order);
    FIELD(MpmWorldDef, gravity);
    FIELD(MpmWorldDef, faces);
    FIELD(MpmWorldDef, wall_friction);
    FIELD(MpmWorldDef, wall_velocity);
    FIELD(MpmWorldDef, exp_terms);
    FIELD(MpmWorldDef, cfl);
    FIELD(MpmWorldDef, max_substeps);
    FIELD(MpmWorldDef, max_volume_ratio);
    FIELD(MpmWorldDef, workers);
    FIELD(MpmWorldDef, effects);
    FIELD(MpmWorldDef, internal_cookie);

    TYPE(MpmMaterialDef);
    FIELD(MpmMaterialDef, model);
    FIELD(MpmMaterialDef, youngs_modulus);
    FIELD(MpmMaterialDef, poisson_ratio);
    FIELD(MpmMaterialDef, density);
    FIELD(MpmMaterialDef, heat_capacity);
    FIELD(MpmMaterialDef, conductivity);
    FIELD(MpmMaterialDef, diffusivity);
    FIELD(MpmMaterialDef, thermal_expansion);
    FIELD(MpmMaterialDef, reference_temperature);
    FIELD(MpmMaterialDef, swelling);
    FIELD(MpmMaterialDef, reference_concentration);
    FIELD(MpmMaterialDef, viscosity);
    FIELD(MpmMaterialDef, bulk_viscosity);
    FIELD(MpmMaterialDef, volume_relaxation);
    FIELD(MpmMaterialDef, bulk_modulus);
    FIELD(MpmMaterialDef, pressure_exponent);
    FIELD(MpmMaterialDef, yield_stress);
    FIELD(MpmMaterialDef, hardening_modulus);
    FIELD(MpmMaterialDef, friction_angle);
    FIELD(MpmMaterialDef, friction_fit);
    FIELD(MpmMaterialDef, cohesion);
    FIELD(MpmMaterialDef, critical_compression);
    FIELD(MpmMaterialDef, critical_stretch);
    FIELD(MpmMaterialDef, hardening_coefficient);
    FIELD(MpmMaterialDef, internal_cookie);

    TYPE(MpmParticlesView);
    FIELD(MpmParticlesView, count);
    FIELD(MpmParticlesView, dimension);
    FIELD(MpmParticlesView, position);
    FIELD(MpmParticlesView, position_low);
    FIELD(MpmParticlesView, velocity);
    FIELD(MpmParticlesView, mass);
    FIELD(MpmParticlesView, volume0);
    FIELD(MpmParticlesView, displacement_gradient);
    FIELD(MpmParticlesView, stress);
    FIELD(MpmParticlesView, material);
    FIELD(MpmParticlesView, status);
    FIELD(MpmParticlesView, force);
    FIELD(MpmParticlesView, damping);
    FIELD(MpmParticlesView, affine);
    FIELD(MpmParticlesView, temperature);
    FIELD(MpmParticlesView, concentration);
    FIELD(MpmParticlesView, grid_temperature);
    FIELD(MpmParticlesView, grid_concentration);
    FIELD(MpmParticlesView, hoop);
    FIELD(MpmParticlesView, plastic);
    FIELD(MpmParticlesView, temperature_source);
    FIELD(MpmParticlesView, concentration_source);

    TYPE(MpmDiagnostics);
    FIELD(MpmDiagnostics, particle_count);
    FIELD(MpmDiagnostics, time);
    FIELD(MpmDiagnostics, step_count);
    FIELD(MpmDiagnostics, mass);
    FIELD(MpmDiagnostics, momentum);
    FIELD(MpmDiagnostics, angular_momentum);
    FIELD(MpmDiagnostics, center_of_mass);
    FIELD(MpmDiagnostics, kinetic);
    FIELD(MpmDiagnostics, strain);
    FIELD(MpmDiagnostics, potential);

    TYPE(MpmMemoryRequirements);
    FIELD(MpmMemoryRequirements, bytes);
    FIELD(MpmMemoryRequirements, align);

    TYPE(MpmParticleArrays);
    FIELD(MpmParticleArrays, position);
    FIELD(MpmParticleArrays, velocity);
    FIELD(MpmParticleArrays, mass);
    FIELD(MpmParticleArrays, volume);
    FIELD(MpmParticleArrays, material);

    TYPE(MpmParticleState);
    FIELD(MpmParticleState, position);
    FIELD(MpmParticleState, position_low);
    FIELD(MpmParticleState, velocity);
    FIELD(MpmParticleState, mass);
    FIELD(MpmParticleState, volume0);
    FIELD(MpmParticleState, displacement_gradient);
    FIELD(MpmParticleState, stress);
    FIELD(MpmParticleState, material);
    FIELD(MpmParticleState, status);
    FIELD(MpmParticleState, force);
    FIELD(MpmParticleState, damping);
    FIELD(MpmParticleState, affine);
    FIELD(MpmParticleState, temperature);
    FIELD(MpmParticleState, concentration);
    FIELD(MpmParticleState, grid_temperature);
    FIELD(MpmParticleState, grid_concentration);
    FIELD(MpmParticleState, hoop);
    FIELD(MpmParticleState, plastic);
    FIELD(MpmParticleState, temperature_source);
    FIELD(MpmParticleState, concentration_source);

    TYPE(MpmIdRange);
    FIELD(MpmIdRange, first);
    FIELD(MpmIdRange, count);

    TYPE(MpmStepReport);
    FIELD(MpmStepReport, substeps);
    FIELD(MpmStepReport, substep_dt);
    FIELD(MpmStepReport, stopped);
    FIELD(MpmStepReport, escaped);
    FIELD(MpmStepReport, frozen);
    FIELD(MpmStepReport, runaway);
    FIELD(MpmStepReport, flags);
    FIELD(MpmStepReport, first_frozen_count);
    FIELD(MpmStepReport, first_frozen);

    TYPE(MpmTaskSystem);
    FIELD(MpmTaskSystem, enqueue_task);
    FIELD(MpmTaskSystem, finish_task);
    FIELD(MpmTaskSystem, user_context);
    FIELD(MpmTaskSystem, worker_count);

    TYPE(MpmColliderDef);
    FIELD(MpmColliderDef, shape);
    FIELD(MpmColliderDef, contact);
    FIELD(MpmColliderDef, radius);
    FIELD(MpmColliderDef, half_length);
    FIELD(MpmColliderDef, half_extents);
    FIELD(MpmColliderDef, inner_radius);
    FIELD(MpmColliderDef, sdf_first);
    FIELD(MpmColliderDef, sdf_dims);
    FIELD(MpmColliderDef, sdf_spacing);
    FIELD(MpmColliderDef, position);
    FIELD(MpmColliderDef, rotation);
    FIELD(MpmColliderDef, velocity);
    FIELD(MpmColliderDef, angular_velocity);
    FIELD(MpmColliderDef, friction);
    FIELD(MpmColliderDef, mass);
    FIELD(MpmColliderDef, inertia);
    FIELD(MpmColliderDef, internal_cookie);

    TYPE(MpmColliderState);
    FIELD(MpmColliderState, def);
    FIELD(MpmColliderState, impulse);
    FIELD(MpmColliderState, angular_impulse);
    FIELD(MpmColliderState, force);
    FIELD(MpmColliderState, torque);
    FIELD(MpmColliderState, duration);

    return 0;
}
