/* A minimal host: it needs a world definition, so it references the default function of the
 * precision it was compiled for. The size check catches a header/library mismatch at run
 * time too, should the link ever succeed. */
#include "mpm_gimp.h"

#include <stdio.h>

int main(void) {
    MpmWorldDef def = mpm_world_def_default();
    MpmMemoryRequirements req;
    MpmStatus status = mpm_memory_requirements(&def, &req);
    if (status != MPM_STATUS_OK) {
        fprintf(stderr, "%s\n", mpm_status_string(status));
        return 1;
    }
    printf("sizeof(mpm_real) = %u, %lu bytes\n", (unsigned)sizeof(mpm_real), (unsigned long)req.bytes);
    return 0;
}
