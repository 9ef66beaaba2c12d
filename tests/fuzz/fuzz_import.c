/* fuzz_import.c: libFuzzer target: bytes -> an asset file assimp reads (PLY, OBJ, STL, OFF, glTF, GLB) -> the
 * tool's import (validation, cbvh's face checks, triangulation, the merge); a clean error or a mesh whose
 * every index and material id is in range. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "import_assimp.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Byte 0 picks the format (its file name's extension) modulo the table; the rest is the file. */
static const char *const formats[] = {"fuzz.ply", "fuzz.obj",  "fuzz.stl",
                                      "fuzz.off", "fuzz.gltf", "fuzz.glb"};

/* assimp's PLY reader loops for ever at the end of a file cut inside its header; the tool ends that import in
 * its child process. In process, the only way out is to stop. */
static void runaway(void *user, const char *path)
{
    (void)user;
    fprintf(stderr,
            "fuzz_import: assimp keeps reading past the end of %s (contained by the tool's child "
            "process, not here)\n",
            path);
    abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    import_options o = {0};
    o.on_runaway_read = runaway;
    imported_mesh m;
    char message[1024];
    const char *name = formats[data[0] % (sizeof formats / sizeof *formats)];
    int rc = import_assimp_memory(data + 1, size - 1, name, &o, &m, message, sizeof message);
    if (rc == 0) {
        if (m.triangle_count == 0 || !m.positions || !m.indices || !m.material_ids)
            abort(); /* success means triangles */
        for (size_t k = 0; k < 3 * m.triangle_count; k++)
            if (m.indices[k] >= m.vertex_count)
                abort();
        /* material ids are assimp's material indices: in range when the scene has materials */
        for (size_t t = 0; m.material_count && t < m.triangle_count; t++)
            if (m.material_ids[t] >= m.material_count)
                abort();
        volatile float sum = 0; /* every position readable */
        for (size_t k = 0; k < 3 * m.vertex_count; k++)
            sum += m.positions[k];
        (void)sum;
        imported_mesh_free(&m);
    } else if (rc != 1 && rc != 2) {
        abort();
    } else if (!message[0]) {
        abort(); /* a failure says why */
    }
    import_options_free(&o);
    return 0;
}
