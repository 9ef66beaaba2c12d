/* material_map.h: `cbvh cook --material-map FILE`: material names to the ids a game uses, and the names a
 * cook stores. */
#ifndef CBVH_TOOLS_MATERIAL_MAP_H
#define CBVH_TOOLS_MATERIAL_MAP_H

#include <stddef.h>
#include <stdint.h>

#include "cbvh.h"
#include "import_assimp.h"

/* A map file: one `NAME<TAB>ID` a line (ID decimal, 0 to 4294967295); `*` as NAME gives the id of every
 * material the other lines do not name; lines starting with # and empty lines are skipped; a CR before
 * the line end is ignored. */
typedef struct material_map_entry {
    char *name;
    uint32_t id;
    unsigned line;
} material_map_entry;

typedef struct material_map {
    material_map_entry *entries; /* in file order */
    size_t count;
    int has_default; /* a `*` line */
    uint32_t default_id;
} material_map;

/* Reads the map at `path`. Returns 0, or 2 (usage: the map is the user's input, wrong for every asset)
 * with `message` naming the file and line. */
int material_map_read(const char *path, material_map *m, char *message, size_t message_size);
void material_map_free(material_map *m);

/* The names a cook of `mesh` stores: each material its triangles use that has a name, once. With `map`
 * (may be NULL) the mesh's material ids become the map's ids first, and the names go with those ids.
 * *names (free it with free(); its strings are the mesh's) and *count receive them. Returns 0; 1 with
 * `message` when a material the mesh uses is not in the map (which has no `*` line); 2 out of memory. */
int material_names_prepare(imported_mesh *mesh, const material_map *map, const char *map_path,
                           cbvh_material_name **names, uint32_t *count, char *message, size_t message_size);

#endif
