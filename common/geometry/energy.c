/* Body energies (energy.h). */
#include "energy.h"

#include "vec.h"

void lahar_body_energy(const lahar_body *b, const lahar_body_state *s, const double gravity[3], double e[3])
{
    e[0] = e[1] = e[2] = 0.0;
    if (b->motion == LAHAR_MOTION_FIXED || !(b->mass > 0.0))
        return;
    vec3 x = v3_load(s->x), v = v3_load(s->v), g = v3_load(gravity);
    e[0] = -b->mass * v3_dot(g, x);
    e[1] = 0.5 * b->mass * v3_dot(v, v);
    vec3 wb = q_rotate_inv(q_load(s->q), v3_load(s->w)); /* body frame: principal axes */
    e[2] = 0.5 * (b->inertia[0] * wb.x * wb.x + b->inertia[1] * wb.y * wb.y + b->inertia[2] * wb.z * wb.z);
}
