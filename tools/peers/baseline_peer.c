/* baseline_peer.c: another build of libcbvh, loaded at run time, as the `baseline` peer of `cbvh bench`. */
#include "config.h"

#ifdef HAVE_DLOPEN

#include <stdio.h>
#include <stdlib.h>

#include "peers.h"

#include <dlfcn.h>

/* The functions of the public API the peer calls, looked up by name in the other build. */
typedef cbvh_result (*open_path_fn)(const char *, const cbvh_allocator *, cbvh_file **, cbvh_error *);
typedef void (*close_fn)(cbvh_file *);
typedef int (*raycast_fn)(const cbvh_file *, const cbvh_ray *, cbvh_traversal, cbvh_hit *,
                          cbvh_query_stats *);
typedef int (*occluded_fn)(const cbvh_file *, const cbvh_ray *, cbvh_traversal, cbvh_query_stats *);
typedef size_t (*scratch_size_fn)(size_t);
typedef void (*raycast_stream_fn)(const cbvh_file *, const cbvh_ray *, size_t, cbvh_hit *, cbvh_query_stats *,
                                  void *, size_t);
typedef void (*occluded_stream_fn)(const cbvh_file *, const cbvh_ray *, size_t, uint8_t *, cbvh_query_stats *,
                                   void *, size_t);

struct baseline_peer {
    void *library;
    cbvh_file *file;
    close_fn close;
    raycast_fn raycast;
    occluded_fn occluded;
    raycast_stream_fn raycast_stream;
    occluded_stream_fn occluded_stream;
    size_t scratch_size; /* a stream call's scratch: its batches' rays, as the other build counts them */
};

/* Its own symbols first (RTLD_DEEPBIND): else its calls from one public function to another would bind to
 * this process's libcbvh, of the same names, and time that. The sanitizers' runtimes refuse RTLD_DEEPBIND;
 * in their builds the baseline's answers are checked, not its speed. */
#if defined(RTLD_DEEPBIND) && !defined(__SANITIZE_ADDRESS__) && !defined(CBVH_SANITIZER_BUILD)
#define BASELINE_DLOPEN_FLAGS (RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND)
#else
#define BASELINE_DLOPEN_FLAGS (RTLD_NOW | RTLD_LOCAL)
#endif

baseline_peer *baseline_peer_open(const char *library, const char *cbvh_path, size_t stream_batch, char *err,
                                  size_t err_size)
{
    baseline_peer *p = calloc(1, sizeof *p);
    if (!p) {
        snprintf(err, err_size, "baseline: out of memory");
        return NULL;
    }
    p->library = dlopen(library, BASELINE_DLOPEN_FLAGS);
    if (!p->library) {
        const char *why = dlerror();
        snprintf(err, err_size, "baseline %s: cannot load it: %s", library, why ? why : "unknown reason");
        free(p);
        return NULL;
    }
    void *open_path = NULL, *scratch_size = NULL;
    struct {
        const char *name;
        void **address;
    } wanted[] = {{"cbvh_open_path", &open_path},
                  {"cbvh_close", (void **)&p->close},
                  {"cbvh_raycast", (void **)&p->raycast},
                  {"cbvh_occluded", (void **)&p->occluded},
                  {"cbvh_stream_scratch_size", &scratch_size},
                  {"cbvh_raycast_stream_scratch", (void **)&p->raycast_stream},
                  {"cbvh_occluded_stream_scratch", (void **)&p->occluded_stream}};
    cbvh_error e;
    for (size_t k = 0; k < sizeof wanted / sizeof wanted[0]; k++) {
        *wanted[k].address = dlsym(p->library, wanted[k].name);
        if (!*wanted[k].address) {
            snprintf(err, err_size, "baseline %s: no function %s: not a build of libcbvh", library,
                     wanted[k].name);
            break;
        }
    }
    if (p->occluded_stream) { /* every function found (the last one looked up) */
        p->scratch_size = ((scratch_size_fn)scratch_size)(stream_batch);
        if (((open_path_fn)open_path)(cbvh_path, NULL, &p->file, &e) == CBVH_OK)
            return p;
        snprintf(err, err_size, "baseline %s: cannot open %s: %s", library, cbvh_path, e.message);
    }
    dlclose(p->library);
    free(p);
    return NULL;
}

void baseline_peer_destroy(baseline_peer *p)
{
    if (!p)
        return;
    p->close(p->file);
    dlclose(p->library);
    free(p);
}

void baseline_peer_raycast(const baseline_peer *p, const cbvh_ray *rays, size_t count, cbvh_hit *hits)
{
    for (size_t i = 0; i < count; i++)
        p->raycast(p->file, &rays[i], CBVH_TRAVERSAL_SORTED, &hits[i], NULL);
}

void baseline_peer_occluded(const baseline_peer *p, const cbvh_ray *rays, size_t count, uint8_t *occluded)
{
    for (size_t i = 0; i < count; i++)
        occluded[i] = (uint8_t)p->occluded(p->file, &rays[i], CBVH_TRAVERSAL_SORTED, NULL);
}

/* Scratch of each call's own, as the bench's cbvh streams have (threads run calls at once). */
void baseline_peer_raycast_stream(const baseline_peer *p, const cbvh_ray *rays, size_t count, cbvh_hit *hits)
{
    void *scratch = malloc(p->scratch_size);
    p->raycast_stream(p->file, rays, count, hits, NULL, scratch, scratch ? p->scratch_size : 0);
    free(scratch);
}

void baseline_peer_occluded_stream(const baseline_peer *p, const cbvh_ray *rays, size_t count,
                                   uint8_t *occluded)
{
    void *scratch = malloc(p->scratch_size);
    p->occluded_stream(p->file, rays, count, occluded, NULL, scratch, scratch ? p->scratch_size : 0);
    free(scratch);
}

#endif
