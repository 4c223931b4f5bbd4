/* The open boundaries of a scene (inlets, outlets, domain; common/scene/inflow.h) <-> scene_t
 * (lcm_types/inlet_t.lcm, outlet_t.lcm). Called by scene_msg.c. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_msg.h"
#include "scene_msg_fields.h"

/* the fields of an inlet and an outlet, listed once (scene_msg_fields.h) */
#define SECTION_ARRAY_FIELDS(X) X(x0) X(e1) X(e2) X(n)
#define INLET_NUM_FIELDS(X) X(level) X(layers) X(velocity) X(t_start) X(t_end) X(max_particles)
#define INLET_ARRAY_FIELDS(X) X(gumbel)

int lahar_scene_msg_inflow_from_case(const lahar_case *c, lahar_scene_t *m)
{
    m->ninlet = c->ninlet;
    m->noutlet = c->noutlet;
    m->inlets = calloc((size_t)(c->ninlet > 0 ? c->ninlet : 1), sizeof *m->inlets);
    m->outlets = calloc((size_t)(c->noutlet > 0 ? c->noutlet : 1), sizeof *m->outlets);
    if (!m->inlets || !m->outlets)
        return -1;
    for (int i = 0; i < c->ninlet; i++) {
        const lahar_inlet *a = &c->inlets[i], *from = a;
        lahar_inlet_t *b = &m->inlets[i], *to = b;
        b->name = (char *)a->name;
        SECTION_ARRAY_FIELDS(COPY_ARRAY)
        INLET_NUM_FIELDS(TO_MSG_NUM)
        INLET_ARRAY_FIELDS(COPY_ARRAY)
        b->kind = (int8_t)a->kind;
        b->ntable = a->ntable;
        b->table_t = a->table_t;
        b->table_v = a->table_v;
        b->nlevel = a->nlevel;
        b->level_t = a->level_t;
        b->level_h = a->level_h;
    }
    for (int i = 0; i < c->noutlet; i++) {
        const lahar_outlet *from = &c->outlets[i];
        lahar_outlet_t *to = &m->outlets[i];
        to->name = (char *)from->name;
        SECTION_ARRAY_FIELDS(COPY_ARRAY)
        to->depth = from->depth;
    }
    m->has_domain = (int8_t)(c->has_domain != 0);
    memcpy(m->domain_lo, c->domain_lo, sizeof m->domain_lo);
    memcpy(m->domain_hi, c->domain_hi, sizeof m->domain_hi);
    return 0;
}

void lahar_scene_msg_inflow_release(lahar_scene_t *m)
{
    free(m->inlets);
    free(m->outlets);
    m->inlets = NULL;
    m->outlets = NULL;
}

int lahar_scene_msg_inflow_to_case(const lahar_scene_t *m, lahar_case *c, char *err, size_t errlen)
{
    if (m->ninlet < 0 || m->noutlet < 0) {
        snprintf(err, errlen, "malformed scene message (inlet/outlet counts)");
        return -1;
    }
    if (m->ninlet > 0 && !(c->inlets = calloc((size_t)m->ninlet, sizeof *c->inlets)))
        goto oom;
    for (int i = 0; i < m->ninlet; i++) {
        const lahar_inlet_t *a = &m->inlets[i];
        lahar_inlet *b = &c->inlets[i];
        c->ninlet = i + 1;
        if (a->kind < LAHAR_HYDRO_CONSTANT || a->kind > LAHAR_HYDRO_TABLE_Q || a->ntable < 0 || !(a->level > 0.0) ||
            a->layers < 0 || a->max_particles < 0 || a->nlevel < 0 ||
            ((a->kind == LAHAR_HYDRO_TABLE_U || a->kind == LAHAR_HYDRO_TABLE_Q) && a->ntable < 1)) {
            snprintf(err, errlen, "malformed scene message (inlet %d)", i);
            return -1;
        }
        const lahar_inlet_t *from = a;
        lahar_inlet *to = b;
        snprintf(b->name, sizeof b->name, "%s", a->name ? a->name : "");
        SECTION_ARRAY_FIELDS(COPY_ARRAY)
        INLET_NUM_FIELDS(TO_MSG_NUM)
        INLET_ARRAY_FIELDS(COPY_ARRAY)
        b->kind = a->kind;
        if (a->ntable > 0) {
            b->table_t = malloc((size_t)a->ntable * sizeof *b->table_t);
            b->table_v = malloc((size_t)a->ntable * sizeof *b->table_v);
            if (!b->table_t || !b->table_v)
                goto oom;
            memcpy(b->table_t, a->table_t, (size_t)a->ntable * sizeof *b->table_t);
            memcpy(b->table_v, a->table_v, (size_t)a->ntable * sizeof *b->table_v);
            b->ntable = a->ntable;
        }
        if (a->nlevel > 0) {
            b->level_t = malloc((size_t)a->nlevel * sizeof *b->level_t);
            b->level_h = malloc((size_t)a->nlevel * sizeof *b->level_h);
            if (!b->level_t || !b->level_h)
                goto oom;
            memcpy(b->level_t, a->level_t, (size_t)a->nlevel * sizeof *b->level_t);
            memcpy(b->level_h, a->level_h, (size_t)a->nlevel * sizeof *b->level_h);
            b->nlevel = a->nlevel;
        }
    }
    if (m->noutlet > 0 && !(c->outlets = calloc((size_t)m->noutlet, sizeof *c->outlets)))
        goto oom;
    for (int i = 0; i < m->noutlet; i++) {
        const lahar_outlet_t *from = &m->outlets[i];
        lahar_outlet *to = &c->outlets[i];
        c->noutlet = i + 1;
        snprintf(to->name, sizeof to->name, "%s", from->name ? from->name : "");
        SECTION_ARRAY_FIELDS(COPY_ARRAY)
        to->depth = from->depth;
    }
    c->has_domain = m->has_domain != 0;
    memcpy(c->domain_lo, m->domain_lo, sizeof c->domain_lo);
    memcpy(c->domain_hi, m->domain_hi, sizeof c->domain_hi);
    return 0;
oom:
    snprintf(err, errlen, "out of memory building the scene");
    return -1;
}
