/* STL import (shape_build.h): ASCII or binary triangles, coincident vertices merged, collapsed
 * triangles dropped, edges built; open and non-convex surfaces allowed (terrain, flumes). */
#include "errmsg.h"
#include "shape_build.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shape_private.h"

/* --- STL ---------------------------------------------------------------------------------------------- */

typedef struct {
    double p[3];
    int id;
} stl_vert;

static int stl_vert_cmp(const void *a, const void *b)
{
    const stl_vert *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x->p[k] != y->p[k])
            return x->p[k] < y->p[k] ? -1 : 1;
    return (x->id > y->id) - (x->id < y->id);
}

static float stl_float_le(const unsigned char *b)
{
    uint32_t u = (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* Read the raw triangle corners (3 per triangle) of an ASCII or binary STL into *out. */
static int stl_read_corners(const char *path, stl_vert **out, int *ncorner, char *err, size_t errlen)
{
    FILE *fp = lahar_fopen_input(path, "rb");
    if (!fp) {
        lahar_errf(err, errlen, "cannot open STL file '%s': %s", path, strerror(errno));
        return -1;
    }
    long size = -1;
    if (fseek(fp, 0, SEEK_END) == 0)
        size = ftell(fp);
    rewind(fp);
    unsigned char hdr[84];
    size_t got = fread(hdr, 1, sizeof hdr, fp);
    stl_vert *v = NULL;
    int n = 0, cap = 0;
    if (got == sizeof hdr) {
        uint32_t ntri = (uint32_t)hdr[80] | (uint32_t)hdr[81] << 8 | (uint32_t)hdr[82] << 16 | (uint32_t)hdr[83] << 24;
        if (size == 84 + 50 * (long)ntri && ntri < (1u << 24)) {
            v = malloc((size_t)(ntri ? ntri : 1) * 3 * sizeof *v);
            if (!v) {
                fclose(fp);
                return -1;
            }
            for (uint32_t t = 0; t < ntri; t++) {
                unsigned char rec[50];
                if (fread(rec, 1, sizeof rec, fp) != sizeof rec) {
                    lahar_errf(err, errlen, "STL file '%s' is truncated", path);
                    free(v);
                    fclose(fp);
                    return -1;
                }
                for (int c = 0; c < 3; c++, n++) {
                    for (int k = 0; k < 3; k++)
                        v[n].p[k] = stl_float_le(rec + 12 + 12 * c + 4 * k);
                    v[n].id = n;
                    if (!isfinite(v[n].p[0]) || !isfinite(v[n].p[1]) || !isfinite(v[n].p[2])) {
                        lahar_errf(err, errlen, "STL file '%s': triangle %u has a coordinate that is not a finite "
                                   "number; repair the mesh", path, (unsigned)t + 1);
                        free(v);
                        fclose(fp);
                        return -1;
                    }
                }
            }
            fclose(fp);
            *out = v;
            *ncorner = n;
            return 0;
        }
    }
    /* ASCII: every "vertex x y z" is a corner; three corners make a facet; "endsolid" ends it (a
     * file cut short, e.g. by a full disk or an interrupted copy, has none) */
    rewind(fp);
    char tok[64];
    int ended = 0, ascii = got >= 5 && memcmp(hdr, "solid", 5) == 0;
    while (fscanf(fp, "%63s", tok) == 1) {
        ended |= strcmp(tok, "endsolid") == 0;
        if (strcmp(tok, "vertex") != 0)
            continue;
        double x, y, z;
        if (fscanf(fp, "%lf %lf %lf", &x, &y, &z) != 3 || !isfinite(x) || !isfinite(y) || !isfinite(z)) {
            lahar_errf(err, errlen, "STL file '%s': vertex %d is not followed by three finite numbers", path, n + 1);
            free(v);
            fclose(fp);
            return -1;
        }
        if (n == cap) {
            cap = cap ? 2 * cap : 96;
            stl_vert *t = realloc(v, (size_t)cap * sizeof *v);
            if (!t) {
                free(v);
                fclose(fp);
                return -1;
            }
            v = t;
        }
        v[n].p[0] = x;
        v[n].p[1] = y;
        v[n].p[2] = z;
        v[n].id = n;
        n++;
    }
    fclose(fp);
    /* a file that does not start with "solid" is still read as ASCII when it holds whole facets and
     * "endsolid" (a byte-order mark or a blank line before "solid"); only one that gives nothing as
     * ASCII either is told about the binary header it failed */
    if (!ascii && got == sizeof hdr && n == 0) {
        uint32_t ntri = (uint32_t)hdr[80] | (uint32_t)hdr[81] << 8 | (uint32_t)hdr[82] << 16 | (uint32_t)hdr[83] << 24;
        lahar_errf(err, errlen, "STL file '%s' is not ASCII STL (it does not start with 'solid'), and as binary STL "
                   "its header's %u triangles need %.0f bytes but the file has %ld: it is cut short or not STL; "
                   "export it again", path, (unsigned)ntri, 84.0 + 50.0 * ntri, size);
        free(v);
        return -1;
    }
    if (n == 0 || n % 3 != 0 || !ended) {
        lahar_errf(err, errlen, "STL file '%s' holds %d vertices%s (neither valid ASCII nor binary STL, or "
                   "cut short); export it again", path, n,
                   n == 0 || n % 3 ? ", not a positive multiple of 3" : " and no 'endsolid' line");
        free(v);
        return -1;
    }
    *out = v;
    *ncorner = n;
    return 0;
}

int lahar_shape_read_stl(lahar_shape *s, const char *path, double radius, char *err, size_t errlen)
{
    memset(s, 0, sizeof *s);
    stl_vert *c = NULL;
    int nc = 0;
    if (stl_read_corners(path, &c, &nc, err, errlen) != 0)
        return -1;
    int rc = -1;
    stl_vert *sorted = malloc((size_t)nc * sizeof *sorted);
    int *uid = malloc((size_t)nc * sizeof *uid), *newid = malloc((size_t)nc * sizeof *newid);
    int *tri = malloc((size_t)nc * sizeof *tri);
    if (!sorted || !uid || !newid || !tri)
        goto done;
    /* merge identical coordinates: sort, give equal runs one id, then renumber by first use */
    memcpy(sorted, c, (size_t)nc * sizeof *c);
    qsort(sorted, (size_t)nc, sizeof *sorted, stl_vert_cmp);
    int nu = 0;
    for (int i = 0; i < nc; i++) {
        if (i > 0 && memcmp(sorted[i].p, sorted[i - 1].p, sizeof sorted[i].p) != 0)
            nu++;
        uid[sorted[i].id] = nu;
    }
    nu++;
    for (int i = 0; i < nu; i++)
        newid[i] = -1;
    int nv = 0;
    for (int i = 0; i < nc; i++)
        if (newid[uid[i]] < 0)
            newid[uid[i]] = nv++;
    int nt = 0;
    for (int t = 0; t < nc / 3; t++) {
        int a = newid[uid[3 * t]], b = newid[uid[3 * t + 1]], d = newid[uid[3 * t + 2]];
        if (a == b || b == d || a == d)
            continue; /* collapsed triangle */
        tri[3 * nt] = a;
        tri[3 * nt + 1] = b;
        tri[3 * nt + 2] = d;
        nt++;
    }
    if (nt == 0) {
        lahar_errf(err, errlen, "STL file '%s' has no non-degenerate triangle", path);
        goto done;
    }
    if (shape_alloc(s, nv, 0, nt, 3 * nt, radius) != 0)
        goto done;
    for (int i = 0; i < nc; i++)
        memcpy(s->v[newid[uid[i]]], c[i].p, sizeof s->v[0]);
    for (int t = 0; t <= nt; t++)
        s->face_start[t] = 3 * t;
    memcpy(s->face_v, tri, (size_t)(3 * nt) * sizeof *tri);
    if (shape_build_edges(s) != 0) {
        lahar_shape_free(s);
        goto done;
    }
    rc = 0;
done:
    free(c);
    free(sorted);
    free(uid);
    free(newid);
    free(tri);
    return rc;
}
