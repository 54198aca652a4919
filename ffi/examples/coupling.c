/*
 * Two-way coupling with a rigid body at a game's frame rate, from C99: a box of 60 kg (per
 * metre of thickness: the world is 2D plane strain, so masses, impulses and forces are per
 * metre) falls into a bed of soft elastic foam, in 60 Hz frames for 3 s.
 *
 * The pattern (README, "Colliders and rigid bodies"): the collider is given the body's mass
 * and moment of inertia, so the world owns its pose during each mpm_world_step and moves it
 * every substep by that substep's impulse and by gravity. After the step the host reads the
 * pose, the velocities and the frame's force back (mpm_world_get_collider) and draws or hands
 * them on; to push the body itself it sets a new pose or velocity between steps
 * (mpm_world_set_collider). A host that integrates the body itself from the impulse read back
 * once a frame holds the body's velocity through the frame's substeps, and a body lighter
 * than the material its contact carries in a frame then rings.
 *
 * Build (from the repository root, after cargo build --release -p mpm-gimp-ffi):
 *   gcc -std=c99 -Wall -Wextra -Werror -pedantic -I ffi/include ffi/examples/coupling.c \
 *       target/release/libmpm_gimp.a -lpthread -ldl -lm -o coupling
 *
 * Output: one line every 0.5 s, then
 *   done t=<s> bottom=<m> speed=<m/s> force=<N/m> weight=<N/m>
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "mpm_gimp.h"

#define CELLS 48
#define ARENA_BYTES ((size_t)4 * 1024 * 1024)
#define ARENA_ALIGN_ROOM 256
static unsigned char arena[ARENA_BYTES + ARENA_ALIGN_ROOM];

static void check(MpmStatus status, const char *call)
{
    if (status != MPM_STATUS_OK) {
        fprintf(stderr, "coupling: %s failed: %s\n", call, mpm_status_string(status));
        exit(EXIT_FAILURE);
    }
}

static MpmVec3 vec2(double x, double y)
{
    MpmVec3 v;
    v.x = (mpm_real)x;
    v.y = (mpm_real)y;
    v.z = (mpm_real)0;
    return v;
}

int main(void)
{
    MpmWorldDef def = mpm_world_def_default();
    def.cell_size = (mpm_real)1 / CELLS;
    def.cells[0] = CELLS;
    def.cells[1] = CELLS;
    def.particle_capacity = 20000;
    def.faces[MPM_FACE_Y_MIN] = MPM_BOUNDARY_STICK;
    def.effects.collider_capacity = 1;
    /* The foam's own losses, so that the body comes to rest. */
    def.effects.damping.declared = 1;
    def.effects.damping.grid.points = 1; /* one point: a constant 60/s */
    def.effects.damping.grid.values[0] = (mpm_real)60;

    MpmMemoryRequirements req;
    check(mpm_memory_requirements(&def, &req), "mpm_memory_requirements");
    size_t offset = (req.align - (size_t)((uintptr_t)arena % req.align)) % req.align;
    if (req.bytes > ARENA_BYTES) {
        fprintf(stderr, "coupling: the world needs %zu bytes: raise ARENA_BYTES\n", req.bytes);
        return EXIT_FAILURE;
    }
    MpmWorld *world = NULL;
    check(mpm_world_init(&def, arena + offset, ARENA_BYTES, &world), "mpm_world_init");

    MpmMaterialDef foam = mpm_material_def_default();
    foam.youngs_modulus = (mpm_real)2e5;
    foam.density = (mpm_real)300;
    uint32_t foam_id = 0;
    check(mpm_world_add_material(world, &foam, &foam_id), "mpm_world_add_material");
    MpmIdRange ids;
    const double lo = 2.0 / CELLS;
    check(mpm_world_fill_box(world, vec2(lo, lo), vec2(1.0 - lo, 0.35), foam_id, vec2(0, 0),
                             &ids),
          "mpm_world_fill_box");

    /* The body: 0.2 m wide, 0.1 m tall, dropped from 0.6 m. Its moment of inertia about its
     * centre, per metre of thickness: m (w^2 + h^2) / 12. */
    const double mass = 60.0, w = 0.2, h = 0.1;
    MpmColliderDef body = mpm_collider_def_default();
    body.shape = MPM_COLLIDER_SHAPE_BOX;
    body.half_extents = vec2(w / 2, h / 2);
    body.half_extents.z = (mpm_real)0.5; /* not read in 2D, but must be > 0 */
    body.position = vec2(0.5, 0.6);
    body.friction = (mpm_real)0.3;
    body.mass = (mpm_real)mass;
    body.inertia.z = (mpm_real)(mass * (w * w + h * h) / 12.0);
    uint32_t body_id = 0;
    check(mpm_world_add_collider(world, &body, &body_id), "mpm_world_add_collider");

    const mpm_real frame = (mpm_real)(1.0 / 60.0);
    MpmColliderState state;
    for (int i = 1; i <= 180; ++i) {
        MpmStepReport report;
        check(mpm_world_step(world, frame, &report), "mpm_world_step");
        check(mpm_world_get_collider(world, body_id, &state), "mpm_world_get_collider");
        if (i % 30 == 0) {
            printf("t=%.2f bottom=%.4f vy=%+.4f force_y=%.1f\n", i / 60.0,
                   (double)state.def.position.y - h / 2, (double)state.def.velocity.y,
                   (double)state.force.y);
        }
    }
    double speed = (double)state.def.velocity.x * (double)state.def.velocity.x +
                   (double)state.def.velocity.y * (double)state.def.velocity.y;
    printf("done t=3 bottom=%.4f speed=%.6f force=%.2f weight=%.2f\n",
           (double)state.def.position.y - h / 2, sqrt(speed),
           (double)state.force.y, mass * 9.81);
    return EXIT_SUCCESS;
}
