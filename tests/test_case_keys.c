/* The key table drives the loader (common/io/case_keys.c): every key of the checked sections is
 * accepted by the loader, its numeric default is what the loader stores, and a value outside the
 * table's range is rejected with the table's message at the key's file:line. A key added to the
 * table but not to the reader (or the other way round) fails here. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "case.h"
#include "case_keys.h"
#include "test_util.h"

/* A small valid 2D case; SECTION's mapping gets "KEY: VALUE" (or nothing when key is NULL). */
static int load_with(const char *section, const char *key, const char *value, lahar_case *c, char *err, size_t n)
{
    char extra[5][160] = {"", "", "", "", ""};
    static const char *const names[] = {"time", "dem", "stability", "checkpoint", "sph"};
    for (int i = 0; i < 5; i++)
        if (key && !strcmp(section, names[i]))
            snprintf(extra[i], sizeof extra[i], "%s: %s%s", key, value, (i == 3 || (i == 0 && !strcmp(key, "end"))) ? "" : ", ");
    /* required keys get their value from `extra` when they are the key under test */
    char end[32] = "end: 0.1", interval[32] = "interval: 0.05", dx[32] = "dx: 0.01, ";
    if (key && !strcmp(section, "time") && !strcmp(key, "end"))
        end[0] = '\0';
    if (key && !strcmp(section, "checkpoint"))
        snprintf(interval, sizeof interval, "%s", strcmp(key, "interval") ? "interval: 0.05, " : "");
    if (key && !strcmp(section, "sph") && !strcmp(key, "dx"))
        dx[0] = '\0';
    char text[2048];
    int len = snprintf(text, sizeof text,
                       "dimensions: 2\n"
                       "time: {%s%s}\n"
                       "materials: {rock: {density: 2650, young: 1e8, restitution: 0.5, friction: 0.5}}\n"
                       "dem: {%sengine: spheropoly}\n"
                       "stability: {%sdensity_band: [0.5, 2.0]}\n"
                       "checkpoint: {%s%s}\n"
                       "bodies: [{name: floor, shape: box, material: rock, motion: fixed, position: [0.05, -0.02],\n"
                       "          size: [0.3, 0.02], radius: 0.001}]\n"
                       "sph: {%s%sblocks: [{box: {lo: [0, 0], hi: [0.1, 0.1]}}]}\n",
                       extra[0], end, extra[1], extra[2], interval, extra[3], dx, extra[4]);
    return lahar_case_load_mem("keys.yaml", text, (size_t)len, c, err, n);
}

/* The same case with a second material `m` of the model that uses KEY (soil keys: model: soil,
 * kn: linear, the rest: hertz), KEY set to VALUE. */
static int load_material(const char *key, const char *value, lahar_case *c, char *err, size_t n)
{
    static const char *const soil_keys[] = {"friction_angle", "cohesion", "dilatancy", "permeability", "damping",
                                            "av_alpha", "av_beta", NULL};
    static const char *const hertz[][2] = {{"density", "2650"}, {"young", "1e8"}, {"restitution", "0.5"},
                                           {"friction", "0.5"}, {NULL, NULL}};
    static const char *const linear[][2] = {{"density", "2650"}, {"kn", "1e6"}, {"restitution", "0.5"},
                                            {"friction", "0.5"}, {NULL, NULL}};
    static const char *const soil[][2] = {{"density", "2000"}, {"young", "1e7"}, {"friction_angle", "30"},
                                          {NULL, NULL}};
    const char *model = "hertz";
    const char *const (*base)[2] = hertz;
    for (int i = 0; soil_keys[i]; i++)
        if (!strcmp(key, soil_keys[i]))
            model = "soil", base = soil;
    if (!strcmp(key, "kn"))
        model = "linear", base = linear;
    char mat[512];
    int k = snprintf(mat, sizeof mat, "model: %s", model);
    for (int i = 0; base[i][0]; i++)
        if (strcmp(base[i][0], key))
            k += snprintf(mat + k, sizeof mat - (size_t)k, ", %s: %s", base[i][0], base[i][1]);
    snprintf(mat + k, sizeof mat - (size_t)k, ", %s: %s", key, value);
    char text[2048];
    int len = snprintf(text, sizeof text,
                       "dimensions: 2\n"
                       "time: {end: 0.1}\n"
                       "materials: {rock: {density: 2650, young: 1e8, restitution: 0.5, friction: 0.5}, m: {%s}}\n"
                       "bodies: [{name: floor, shape: box, material: rock, motion: fixed, position: [0.05, -0.02],\n"
                       "          size: [0.3, 0.02], radius: 0.001}]\n"
                       "sph: {dx: 0.01, blocks: [{box: {lo: [0, 0], hi: [0.1, 0.1]}}]}\n",
                       mat);
    return lahar_case_load_mem("keys.yaml", text, (size_t)len, c, err, n);
}

/* A value of key k just outside its range (below lo, else above hi) as text, and the table's
 * message for it. */
static void outside(const lahar_key *k, char value[64], char want[512])
{
    double bad = k->range & LAHAR_KEY_LO ? k->lo - 1.0 : k->hi + 1.0;
    if (k->range & LAHAR_KEY_LO_OPEN && k->range & LAHAR_KEY_LO)
        bad = k->lo;
    snprintf(value, 64, "%.17g", bad);
    lahar_key_range_error(k, bad, want, 512);
}

int main(void)
{
    static const char *const checked[] = {"time", "dem", "stability", "checkpoint", "sph"};
    char err[1024];
    lahar_case c;
    CHECK(load_with("", NULL, NULL, &c, err, sizeof err) == 0, "the base case does not load: %s", err);
    lahar_case_free(&c);
    /* stored defaults against the table's (keys whose default is a plain number) */
    typedef struct { const char *section, *key; double stored; } stored_default;
    stored_default defaults[16];
    int nd = 0;
    if (load_with("", NULL, NULL, &c, err, sizeof err) == 0) {
        defaults[nd++] = (stored_default){"time", "dt_min", c.dt_min};
        defaults[nd++] = (stored_default){"time", "forces_interval", c.forces_interval};
        defaults[nd++] = (stored_default){"dem", "dt_safety", c.dem_dt_safety};
        defaults[nd++] = (stored_default){"stability", "max_overlap", c.stability.max_overlap};
        defaults[nd++] = (stored_default){"sph", "density", c.sph_density};
        defaults[nd++] = (stored_default){"sph", "h_over_dx", c.sph.h_over_dx};
        defaults[nd++] = (stored_default){"sph", "gamma", c.sph.gamma};
        defaults[nd++] = (stored_default){"sph", "viscosity", c.sph.mu};
        defaults[nd++] = (stored_default){"sph", "alpha", c.sph.alpha};
        defaults[nd++] = (stored_default){"sph", "delta", c.sph.delta};
        defaults[nd++] = (stored_default){"sph", "cfl", c.sph.cfl};
        defaults[nd++] = (stored_default){"sph", "cfl_force", c.sph.cfl_force};
        defaults[nd++] = (stored_default){"sph", "cfl_visc", c.sph.cfl_visc};
        defaults[nd++] = (stored_default){"sph", "sps_cs", c.sph.sps_cs};
        defaults[nd++] = (stored_default){"sph", "shifting", c.sph.shifting};
        lahar_case_free(&c);
    }
    for (int i = 0; i < nd; i++) {
        const lahar_key *k = lahar_key_find(lahar_key_section_find(defaults[i].section), defaults[i].key);
        CHECK(k && lahar_key_default(k) == defaults[i].stored, "%s.%s: the loader stores %g, the table says %s",
              defaults[i].section, defaults[i].key, defaults[i].stored, k ? k->def : "(no entry)");
    }
    int tested = 0;
    for (size_t s = 0; s < sizeof checked / sizeof checked[0]; s++) {
        const lahar_key_section *sec = lahar_key_section_find(checked[s]);
        CHECK(sec != NULL, "no table for section %s", checked[s]);
        for (const lahar_key *k = sec ? sec->keys : NULL; k && k->name; k++) {
            if (k->type != LAHAR_KEY_NUMBER && k->type != LAHAR_KEY_WHOLE)
                continue;
            /* accepted: an unknown key would say so */
            if (load_with(checked[s], k->name, "1e300", &c, err, sizeof err) == 0)
                lahar_case_free(&c);
            CHECK(!strstr(err, "unknown key"), "%s.%s is in the table but the loader does not know it: %s", checked[s],
                  k->name, err);
            if (!(k->range & (LAHAR_KEY_LO | LAHAR_KEY_HI)))
                continue;
            char value[64], want[512], path[96];
            outside(k, value, want);
            snprintf(path, sizeof path, "%s.%s: ", checked[s], k->name);
            int rc = load_with(checked[s], k->name, value, &c, err, sizeof err);
            if (rc == 0)
                lahar_case_free(&c);
            CHECK(rc != 0 && strstr(err, path) && strstr(err, want), "%s = %s: want '%s%s', got '%s'", path, value,
                  path, want, rc ? err : "(loaded)");
            tested++;
        }
    }
    /* materials.NAME: each numeric key with a range, on a material of the model that uses it */
    const lahar_key_section *ms = lahar_key_section_find("materials.NAME");
    CHECK(ms != NULL, "no table for materials.NAME");
    int tested_mat = 0;
    for (const lahar_key *k = ms ? ms->keys : NULL; k && k->name; k++) {
        if (k->type != LAHAR_KEY_NUMBER || !(k->range & (LAHAR_KEY_LO | LAHAR_KEY_HI)))
            continue;
        char value[64], want[512], path[96];
        outside(k, value, want);
        snprintf(path, sizeof path, "materials.m.%s: ", k->name);
        int rc = load_material(k->name, value, &c, err, sizeof err);
        if (rc == 0)
            lahar_case_free(&c);
        CHECK(rc != 0 && strstr(err, path) && strstr(err, want), "%s = %s: want '%s%s', got '%s'", path, value, path,
              want, rc ? err : "(loaded)");
        tested_mat++;
    }
    CHECK(tested_mat >= 12, "only %d material range checks exercised", tested_mat);
    tested += tested_mat;
    /* the materials' numeric defaults as stored */
    if (load_material("cohesion", "0", &c, err, sizeof err) == 0) {
        const lahar_material *mt = &c.materials[1];
        const char *names[] = {"dilatancy", "permeability", "damping", "av_alpha", "av_beta"};
        const double stored[] = {mt->dilatancy, mt->permeability, mt->damping, mt->av_alpha, mt->av_beta};
        for (int i = 0; i < 5; i++) {
            const lahar_key *k = lahar_key_find(ms, names[i]);
            CHECK(k && lahar_key_default(k) == stored[i], "materials.NAME.%s: the loader stores %g, the table says %s",
                  names[i], stored[i], k ? k->def : "(no entry)");
            nd++;
        }
        lahar_case_free(&c);
    } else
        CHECK(0, "the soil material case does not load: %s", err);
    /* the sph choices are read as the index of the value in the table's list: that list must be in
     * the order of the C enum stored (scene.h) */
    static const char *const choice_keys[] = {"eos", "wall_viscous", "initial_pressure", "wall_pressure",
                                              "penalty_stiffness", "scheme"};
    const lahar_key_section *ss = lahar_key_section_find("sph");
    int nchoice = 0;
    for (size_t q = 0; q < sizeof choice_keys / sizeof choice_keys[0]; q++) {
        const lahar_key *k = lahar_key_find(ss, choice_keys[q]);
        CHECK(k && k->choices, "sph.%s: no choices in the table", choice_keys[q]);
        for (int v = 0; k && k->choices && k->choices[v]; v++) {
            if (load_with("sph", k->name, k->choices[v], &c, err, sizeof err) != 0) {
                CHECK(0, "sph.%s: %s does not load: %s", k->name, k->choices[v], err);
                continue;
            }
            const int stored[] = {(int)c.sph.eos, (int)c.sph.wall_viscous, (int)c.sph.initial_pressure,
                                  (int)c.sph.wall_pressure, (int)c.sph.penalty_stiffness, (int)c.sph.scheme};
            CHECK(stored[q] == v, "sph.%s: %s is choice %d of the table but the loader stores %d", k->name,
                  k->choices[v], v, stored[q]);
            lahar_case_free(&c);
            nchoice++;
        }
    }
    CHECK(nchoice >= 12, "only %d choices checked", nchoice);
    /* bodies[]: a shape-specific key (the table's `only`) on a disc, which none of them belongs to, is
     * refused as unknown; on a shape it belongs to it is known */
    const lahar_key_section *bs = lahar_key_section_find("bodies[]");
    int shape_keys = 0;
    for (const lahar_key *k = bs ? bs->keys : NULL; k && k->name; k++) {
        if (!k->only)
            continue;
        CHECK(!lahar_key_applies(k, "disc"), "bodies[].%s: a disc has no shape-specific keys", k->name);
        char text[1024], want[96];
        int len = snprintf(text, sizeof text,
                           "dimensions: 2\ntime: {end: 0.1}\n"
                           "materials: {rock: {density: 2650, young: 1e8, restitution: 0.5, friction: 0.5}}\n"
                           "bodies: [{name: b, shape: disc, material: rock, radius: 0.01, %s: 1}]\n", k->name);
        snprintf(want, sizeof want, "bodies[0].%s: unknown key", k->name);
        int rc = lahar_case_load_mem("keys.yaml", text, (size_t)len, &c, err, sizeof err);
        if (rc == 0)
            lahar_case_free(&c);
        CHECK(rc != 0 && strstr(err, want), "want '%s', got '%s'", want, rc ? err : "(loaded)");
        shape_keys++;
    }
    CHECK(shape_keys >= 6, "only %d shape-specific body keys", shape_keys);
    CHECK(tested >= 20, "only %d range checks exercised", tested);
    printf("%d keys' ranges checked against the loader, %d defaults\n", tested, nd);
    return failures != 0;
}
