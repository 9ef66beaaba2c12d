/* consumer.c: a program built against cbvh::cbvh: cooks a quad when the library has the cooker, else reads
 * the given quad file, then casts one ray and prints what it hit. */
#include <math.h>
#include <stdio.h>

#include <cbvh.h>

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr,
                "usage: consumer FILE.cbvh (written when the library has the cooker, read otherwise)\n");
        return 2;
    }
    cbvh_error err;
#if CBVH_HAVE_COOKER
    static const float positions[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    static const uint32_t indices[] = {0, 1, 2, 0, 2, 3};
    cbvh_mesh mesh = {positions, 4, 0, indices, 2, NULL};
    cbvh_cook_options options;
    cbvh_cook_options_init(&options, sizeof options);
    if (cbvh_cook_to_path(&mesh, &options, NULL, argv[1], NULL, &err) != CBVH_OK) {
        fprintf(stderr, "cook: %s\n", err.message);
        return 1;
    }
    printf("cooker: yes\n");
#else
    printf("cooker: no\n");
#endif
    cbvh_file *file;
    if (cbvh_open_path_read(argv[1], NULL, &file, &err) != CBVH_OK) {
        fprintf(stderr, "open: %s\n", err.message);
        return 1;
    }
    cbvh_file_info info;
    cbvh_file_get_info(file, &info, sizeof info);
    /* straight down through the first triangle of a quad: 3/4 across x, 1/4 across y */
    cbvh_ray ray = {{info.bounds_min[0] + 0.75f * (info.bounds_max[0] - info.bounds_min[0]),
                     info.bounds_min[1] + 0.25f * (info.bounds_max[1] - info.bounds_min[1]),
                     info.bounds_max[2] + 1.0f},
                    0.0f,
                    {0.0f, 0.0f, -1.0f},
                    INFINITY};
    cbvh_hit hit;
    if (cbvh_raycast(file, &ray, CBVH_TRAVERSAL_SORTED, &hit, NULL))
        printf("%u triangles; hit triangle %u at t = %g\n", info.triangle_count, hit.tri, hit.t);
    else
        printf("%u triangles; miss\n", info.triangle_count);
    cbvh_close(file);
    return 0;
}
