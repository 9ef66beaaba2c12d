/* sweep_features.c: the normal of a contact at zero distance. */
#include "query/sweep_features.h"

cbvh_v3 cbvh_fallback_normal(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 d)
{
    cbvh_v3 n = v3_normalize(v3_cross(v3_sub(b, a), v3_sub(c, a)));
    if (v3_len2(n) == 0.0) {
        n = v3_normalize(v3_scale(d, -1.0));
        return v3_len2(n) == 0.0 ? v3(0.0, 0.0, 1.0) : n;
    }
    return v3_dot(n, d) > 0.0 ? v3_scale(n, -1.0) : n;
}
