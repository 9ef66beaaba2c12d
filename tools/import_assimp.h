/* import_assimp.h: reading any mesh file assimp understands into one merged triangle list. */
#ifndef CBVH_TOOLS_IMPORT_ASSIMP_H
#define CBVH_TOOLS_IMPORT_ASSIMP_H

#include <stddef.h>
#include <stdint.h>

/* A merged triangle mesh, owned by the importer (free with imported_mesh_free).
 *
 * Order (this defines the "original triangle ids" queries report): depth-first over the node
 * hierarchy from the root, a node's own meshes in order before its children, children in order;
 * for each mesh reference its triangles in the mesh's face order (after assimp's triangulation
 * of polygons). A mesh referenced by several nodes is emitted once per reference, each time
 * with that node's accumulated transform (computed in double precision, stored as float).
 * Material id = assimp's material index of the mesh. Points and lines are dropped and counted. */
typedef struct imported_mesh {
    float *positions; /* vertex_count x 3 */
    size_t vertex_count;
    uint32_t *indices;      /* triangle_count x 3 */
    uint32_t *material_ids; /* triangle_count */
    size_t triangle_count;
    uint64_t dropped_points; /* point primitives dropped */
    uint64_t dropped_lines;  /* line primitives dropped */
    uint32_t mesh_instances; /* mesh references emitted */
    uint32_t material_count; /* materials in the scene */
    char **material_names;   /* material_count names (assimp's AI_MATKEY_NAME; NULL when it has none), or
                              * NULL when there are no materials */
} imported_mesh;

/* A list of file names, each once, in first-seen order. */
typedef struct path_list {
    char **paths;
    size_t count;
} path_list;

/* What an import keeps and what it records; zeroed means everything. */
typedef struct import_options {
    const char *select; /* fnmatch(3) pattern: only nodes whose names match, with their subtrees; NULL: all */
    path_list opened;   /* out: every file the import opened (the input, .mtl, .bin ... side files) */
    path_list missing;  /* out: files the import looked for and did not find (a .mtl the asset names ...) */
    /* Called (when set) once assimp has asked a file for more bytes at its end many thousand times: its
     * reader is looping on a truncated file and will not stop; the hook may end the process. */
    void (*on_runaway_read)(void *hook_user, const char *path);
    /* Called (when set) as assimp reads through the input file: the fraction read, in whole percents. */
    void (*on_read_progress)(void *hook_user, int percent);
    void *hook_user;
} import_options;

/* Reads `path` with assimp, through a file system that records in `o` what the import opened and what it
 * looked for in vain: assimp parses and validates (aiProcess_ValidateDataStructure), cbvh checks every
 * face's indices and kinds, then assimp triangulates (aiProcess_Triangulate | aiProcess_JoinIdenticalVertices
 * | aiProcess_SortByPType). A name ending in ".gz" is inflated first and read as the name without ".gz"
 * (e.g. mesh.obj.gz: its format and the folder of its side files). Returns 0 on success; otherwise writes
 * a message to `message` and returns 2 when the file cannot be read, 1 when it is not a usable mesh (with
 * o->select: also when no node matches). `o` may be NULL. Safe on untrusted files as far as cbvh's checks
 * reach; assimp's parsers themselves may still crash, hang or abort on some (import_contained runs this
 * in a child process for that). */
int import_assimp(const char *path, import_options *o, imported_mesh *out, char *message,
                  size_t message_size);

/* As import_assimp, on `size` bytes read as the file `name` (its extension picks the format; side files are
 * looked for beside it on disk). */
int import_assimp_memory(const void *data, size_t size, const char *name, import_options *o,
                         imported_mesh *out, char *message, size_t message_size);

void import_options_free(import_options *o);

void imported_mesh_free(imported_mesh *m);

#endif
