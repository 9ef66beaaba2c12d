/* material_map.c: reads --material-map files and turns a mesh's assimp material indices into stored ids and
 * names. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "material_map.h"

void material_map_free(material_map *m)
{
    for (size_t k = 0; k < m->count; k++)
        free(m->entries[k].name);
    free(m->entries);
    memset(m, 0, sizeof *m);
}

/* The entry named `name`, or NULL. */
static const material_map_entry *map_find(const material_map *m, const char *name)
{
    for (size_t k = 0; k < m->count; k++)
        if (!strcmp(m->entries[k].name, name))
            return &m->entries[k];
    return NULL;
}

/* Parses a decimal id 0..UINT32_MAX that is the whole of `s`. */
static int parse_id(const char *s, uint32_t *id)
{
    if (*s < '0' || *s > '9')
        return 0;
    uint64_t v = 0;
    for (; *s >= '0' && *s <= '9'; s++) {
        v = 10 * v + (uint64_t)(*s - '0');
        if (v > UINT32_MAX)
            return 0;
    }
    *id = (uint32_t)v;
    return *s == '\0';
}

/* One line (without its newline); returns 0 or 2 with `message`. */
static int map_line(material_map *m, const char *path, unsigned line_no, char *line, char *message,
                    size_t message_size)
{
    size_t len = strlen(line);
    if (len > 0 && line[len - 1] == '\r')
        line[--len] = '\0';
    if (len == 0 || line[0] == '#')
        return 0;
    char *tab = strrchr(line, '\t');
    uint32_t id;
    if (!tab || tab == line || !parse_id(tab + 1, &id)) {
        snprintf(message, message_size, "%s:%u: expected NAME<TAB>ID with ID a whole number 0 to 4294967295",
                 path, line_no);
        return 2;
    }
    *tab = '\0';
    if (!strcmp(line, "*")) {
        if (m->has_default) {
            snprintf(message, message_size, "%s:%u: a second '*' line", path, line_no);
            return 2;
        }
        m->has_default = 1;
        m->default_id = id;
        return 0;
    }
    const material_map_entry *seen = map_find(m, line);
    if (seen) {
        snprintf(message, message_size, "%s:%u: material '%s' is mapped already on line %u", path, line_no,
                 line, seen->line);
        return 2;
    }
    material_map_entry *grown = realloc(m->entries, (m->count + 1) * sizeof *grown);
    if (!grown || !(grown[m->count].name = strdup(line))) {
        if (grown)
            m->entries = grown;
        snprintf(message, message_size, "%s:%u: out of memory", path, line_no);
        return 2;
    }
    m->entries = grown;
    m->entries[m->count].id = id;
    m->entries[m->count].line = line_no;
    m->count++;
    return 0;
}

int material_map_read(const char *path, material_map *m, char *message, size_t message_size)
{
    memset(m, 0, sizeof *m);
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(message, message_size, "%s: cannot open the material map: %s", path, strerror(errno));
        return 2;
    }
    char *line = NULL;
    size_t cap = 0;
    unsigned line_no = 0;
    int rc = 0;
    while (rc == 0 && getline(&line, &cap, f) >= 0) {
        line_no++;
        line[strcspn(line, "\n")] = '\0';
        rc = map_line(m, path, line_no, line, message, message_size);
    }
    if (rc == 0 && ferror(f)) {
        snprintf(message, message_size, "%s: cannot read the material map: %s", path, strerror(errno));
        rc = 2;
    }
    free(line);
    fclose(f);
    if (rc)
        material_map_free(m);
    return rc;
}

/* The name of material `k` of the mesh, or NULL (no name, or an id past the scene's materials). */
static const char *material_name(const imported_mesh *mesh, uint32_t k)
{
    return mesh->material_names && k < mesh->material_count ? mesh->material_names[k] : NULL;
}

/* With a map: each used material's new id in `to` (indexed by material; used[] says which). */
static int map_ids(const imported_mesh *mesh, const material_map *map, const char *map_path,
                   const uint64_t *uses, uint32_t slots, uint32_t *to, char *message, size_t message_size)
{
    for (uint32_t k = 0; k < slots; k++) {
        if (!uses[k])
            continue;
        const char *name = material_name(mesh, k);
        const material_map_entry *e = name ? map_find(map, name) : NULL;
        if (e) {
            to[k] = e->id;
        } else if (map->has_default) {
            to[k] = map->default_id;
        } else {
            if (name)
                snprintf(message, message_size,
                         "material '%s' (%llu triangles) is not in the material map %s, "
                         "which has no '*' line",
                         name, (unsigned long long)uses[k], map_path);
            else
                snprintf(message, message_size,
                         "%llu triangles have a material without a name (%s %u), and the "
                         "material map %s has no '*' line",
                         (unsigned long long)uses[k], k < mesh->material_count ? "material" : "ids from", k,
                         map_path);
            return 1;
        }
    }
    return 0;
}

int material_names_prepare(imported_mesh *mesh, const material_map *map, const char *map_path,
                           cbvh_material_name **names, uint32_t *count, char *message, size_t message_size)
{
    *names = NULL;
    *count = 0;
    if (!mesh->material_ids)
        return 0;
    /* Materials used, by index: ids past the scene's materials (none have names) share one last slot. */
    const uint32_t slots = mesh->material_count + 1;
    uint64_t *uses = calloc(slots, sizeof *uses);
    uint32_t *to = calloc(slots, sizeof *to);
    cbvh_material_name *out = calloc(slots, sizeof *out);
    int rc = uses && to && out ? 0 : 2;
    if (rc)
        snprintf(message, message_size, "out of memory for %u materials", mesh->material_count);
    for (size_t t = 0; rc == 0 && t < mesh->triangle_count; t++) {
        const uint32_t k = mesh->material_ids[t];
        uses[k < mesh->material_count ? k : mesh->material_count]++;
    }
    if (rc == 0 && map) {
        /* the last slot stands for ids without a name: any of them maps as an unnamed material */
        rc = map_ids(mesh, map, map_path, uses, slots, to, message, message_size);
        for (size_t t = 0; rc == 0 && t < mesh->triangle_count; t++) {
            const uint32_t k = mesh->material_ids[t];
            mesh->material_ids[t] = to[k < mesh->material_count ? k : mesh->material_count];
        }
    }
    for (uint32_t k = 0; rc == 0 && k < mesh->material_count; k++) {
        if (!uses[k] || !material_name(mesh, k))
            continue;
        out[*count].id = map ? to[k] : k;
        out[*count].name = material_name(mesh, k);
        (*count)++;
    }
    free(uses);
    free(to);
    if (rc || *count == 0) {
        free(out);
        out = NULL;
        *count = 0;
    }
    *names = out;
    return rc;
}
