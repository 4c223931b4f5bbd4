/* XDMF 2 text for lahar's HDF5 output (see xdmf.h). Plain text generation: XDMF is XML whose
 * light data we write with snprintf; the heavy data stays in HDF5. */
#include "xdmf.h"
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>
#include "output.h"

static const char xdmf_header[] =
    "<?xml version=\"1.0\" ?>\n"
    "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    "<Xdmf Version=\"2.0\">\n"
    " <Domain>\n"
    "  <Grid Name=\"lahar\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
static const char xdmf_footer[] = "  </Grid>\n </Domain>\n</Xdmf>\n";

int lahar_xdmf_open(lahar_xdmf_file *f, const char *path, char *err, size_t n)
{
    f->fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (f->fd < 0) {
        snprintf(err, n, "%s: cannot create (%s)", path, strerror(errno));
        return -1;
    }
    size_t lh = sizeof xdmf_header - 1, lf = sizeof xdmf_footer - 1;
    if (pwrite(f->fd, xdmf_header, lh, 0) != (ssize_t)lh || pwrite(f->fd, xdmf_footer, lf, (off_t)lh) != (ssize_t)lf) {
        snprintf(err, n, "%s: write failed (%s)", path, strerror(errno));
        close(f->fd);
        f->fd = -1;
        return -1;
    }
    f->tail = (off_t)lh;
    return 0;
}

int lahar_xdmf_append(lahar_xdmf_file *f, char *buf, size_t len, size_t cap)
{
    size_t lf = sizeof xdmf_footer - 1;
    if (f->fd < 0 || len + lf + 1 > cap)
        return -1;
    /* One pwrite of step + footer over the old footer: the file only grows, and a reader sees
     * either the old complete document or the new one (plus at worst a torn tail for the
     * microseconds of the write). */
    memcpy(buf + len, xdmf_footer, lf + 1);
    if (pwrite(f->fd, buf, len + lf, f->tail) != (ssize_t)(len + lf))
        return -1;
    f->tail += (off_t)len;
    return 0;
}

void lahar_xdmf_close(lahar_xdmf_file *f)
{
    if (f->fd >= 0)
        close(f->fd);
    f->fd = -1;
}

/* snprintf into buf at *pos, tracking the size that would have been needed. */
#define XAPPEND(...)                                                                       \
    do {                                                                                   \
        int k_ = snprintf(buf + (pos < cap ? pos : cap), pos < cap ? cap - pos : 0, __VA_ARGS__); \
        if (k_ > 0)                                                                        \
            pos += (size_t)k_;                                                             \
    } while (0)

size_t lahar_xdmf_step_begin(char *buf, size_t cap, int64_t step, double t)
{
    size_t pos = 0;
    XAPPEND("   <Grid Name=\"step_%" PRId64 "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n"
            "    <Time Value=\"%.17g\"/>\n",
            step, t);
    return pos;
}

size_t lahar_xdmf_step_end(char *buf, size_t cap)
{
    size_t pos = 0;
    XAPPEND("   </Grid>\n");
    return pos;
}

static size_t xdmf_dataitem(char *buf, size_t cap, const char *dims, const char *type, int prec, const char *h5,
                            const char *path)
{
    size_t pos = 0;
    XAPPEND("       <DataItem Dimensions=\"%s\" NumberType=\"%s\" Precision=\"%d\" Format=\"HDF\">%s:%s</DataItem>\n",
            dims, type, prec, h5, path);
    return pos;
}

size_t lahar_xdmf_bodies_grids(char *buf, size_t cap, const lahar_xdmf_bodies *b, int64_t snap)
{
    size_t pos = 0;
    char dims[64], path[128];
    const char *topo = b->nodes_per_cell == 3 ? "Triangle" : "Polyline";
    if (b->moving_cells > 0) {
        XAPPEND("    <Grid Name=\"bodies\" GridType=\"Uniform\">\n"
                "     <Topology TopologyType=\"%s\" NodesPerElement=\"%d\" NumberOfElements=\"%" PRId64 "\">\n",
                topo, b->nodes_per_cell, b->moving_cells);
        snprintf(dims, sizeof dims, "%" PRId64 " %d", b->moving_cells, b->nodes_per_cell);
        pos += xdmf_dataitem(buf + (pos < cap ? pos : cap), pos < cap ? cap - pos : 0, dims, "Int", 4, b->h5name,
                             "/geometry/moving/cells");
        XAPPEND("     </Topology>\n     <Geometry GeometryType=\"XYZ\">\n");
        snprintf(dims, sizeof dims, "%" PRId64 " 3", b->moving_vertices);
        snprintf(path, sizeof path, "/snapshots/%06" PRId64 "/vertices", snap);
        pos += xdmf_dataitem(buf + (pos < cap ? pos : cap), pos < cap ? cap - pos : 0, dims, "Float", 4, b->h5name, path);
        XAPPEND("     </Geometry>\n     <Attribute Name=\"body_id\" AttributeType=\"Scalar\" Center=\"Cell\">\n");
        snprintf(dims, sizeof dims, "%" PRId64, b->moving_cells);
        pos += xdmf_dataitem(buf + (pos < cap ? pos : cap), pos < cap ? cap - pos : 0, dims, "Int", 4, b->h5name,
                             "/geometry/moving/body_id");
        XAPPEND("     </Attribute>\n     <Attribute Name=\"velocity\" AttributeType=\"Vector\" Center=\"Node\">\n");
        snprintf(dims, sizeof dims, "%" PRId64 " 3", b->moving_vertices);
        snprintf(path, sizeof path, "/snapshots/%06" PRId64 "/vertex_velocity", snap);
        pos += xdmf_dataitem(buf + (pos < cap ? pos : cap), pos < cap ? cap - pos : 0, dims, "Float", 4, b->h5name, path);
        XAPPEND("     </Attribute>\n    </Grid>\n");
    }
    if (b->fixed_cells > 0) {
        XAPPEND("    <Grid Name=\"fixed_bodies\" GridType=\"Uniform\">\n"
                "     <Topology TopologyType=\"%s\" NodesPerElement=\"%d\" NumberOfElements=\"%" PRId64 "\">\n",
                topo, b->nodes_per_cell, b->fixed_cells);
        snprintf(dims, sizeof dims, "%" PRId64 " %d", b->fixed_cells, b->nodes_per_cell);
        pos += xdmf_dataitem(buf + (pos < cap ? pos : cap), pos < cap ? cap - pos : 0, dims, "Int", 4, b->h5name,
                             "/geometry/fixed/cells");
        XAPPEND("     </Topology>\n     <Geometry GeometryType=\"XYZ\">\n");
        snprintf(dims, sizeof dims, "%" PRId64 " 3", b->fixed_vertices);
        pos += xdmf_dataitem(buf + (pos < cap ? pos : cap), pos < cap ? cap - pos : 0, dims, "Float", 4, b->h5name,
                             "/geometry/fixed/vertices");
        XAPPEND("     </Geometry>\n     <Attribute Name=\"body_id\" AttributeType=\"Scalar\" Center=\"Cell\">\n");
        snprintf(dims, sizeof dims, "%" PRId64, b->fixed_cells);
        pos += xdmf_dataitem(buf + (pos < cap ? pos : cap), pos < cap ? cap - pos : 0, dims, "Int", 4, b->h5name,
                             "/geometry/fixed/body_id");
        XAPPEND("     </Attribute>\n    </Grid>\n");
    }
    if (b->nbody > 0) {
        static const char *const vec_name[] = {"velocity", "angular_velocity"};
        XAPPEND("    <Grid Name=\"body_centres\" GridType=\"Uniform\">\n"
                "     <Topology TopologyType=\"Polyvertex\" NodesPerElement=\"1\" NumberOfElements=\"%d\"/>\n"
                "     <Geometry GeometryType=\"XYZ\">\n",
                b->nbody);
        snprintf(dims, sizeof dims, "%d 3", b->nbody);
        snprintf(path, sizeof path, "/snapshots/%06" PRId64 "/position", snap);
        pos += xdmf_dataitem(buf + (pos < cap ? pos : cap), pos < cap ? cap - pos : 0, dims, "Float", 8, b->h5name, path);
        XAPPEND("     </Geometry>\n");
        for (int k = 0; k < 2; k++) {
            XAPPEND("     <Attribute Name=\"%s\" AttributeType=\"Vector\" Center=\"Node\">\n", vec_name[k]);
            snprintf(path, sizeof path, "/snapshots/%06" PRId64 "/%s", snap, vec_name[k]);
            pos += xdmf_dataitem(buf + (pos < cap ? pos : cap), pos < cap ? cap - pos : 0, dims, "Float", 8, b->h5name,
                                 path);
            XAPPEND("     </Attribute>\n");
        }
        XAPPEND("     <Attribute Name=\"body_id\" AttributeType=\"Scalar\" Center=\"Node\">\n");
        snprintf(dims, sizeof dims, "%d", b->nbody);
        pos += xdmf_dataitem(buf + (pos < cap ? pos : cap), pos < cap ? cap - pos : 0, dims, "Int", 4, b->h5name,
                             "/header/body_id");
        XAPPEND("     </Attribute>\n    </Grid>\n");
    }
    return pos;
}

size_t lahar_xdmf_particles_grid(char *buf, size_t cap, const lahar_xdmf_particles *p, int64_t snap, int64_t n)
{
    static const struct {
        unsigned field;
        const char *name, *type;
        int prec;
    } attr[] = {
        {LAHAR_PFIELD_VELOCITY, "vx", "Float", 8},  {LAHAR_PFIELD_VELOCITY, "vy", "Float", 8},
        {LAHAR_PFIELD_VELOCITY, "vz", "Float", 8},  {LAHAR_PFIELD_DENSITY, "density", "Float", 8},
        {LAHAR_PFIELD_PRESSURE, "pressure", "Float", 8}, {LAHAR_PFIELD_PHASE, "phase", "Int", 4},
        {LAHAR_PFIELD_ID, "id", "Int", 8},
    };
    size_t pos = 0;
    char dims[32], path[128];
    snprintf(dims, sizeof dims, "%" PRId64, n);
    XAPPEND("    <Grid Name=\"particles\" GridType=\"Uniform\">\n"
            "     <Topology TopologyType=\"Polyvertex\" NodesPerElement=\"1\" NumberOfElements=\"%" PRId64 "\"/>\n"
            "     <Geometry GeometryType=\"X_Y_Z\">\n",
            n);
    for (int k = 0; k < 3; k++) {
        snprintf(path, sizeof path, "/snapshots/%06" PRId64 "/%c", snap, "xyz"[k]);
        pos += xdmf_dataitem(buf + (pos < cap ? pos : cap), pos < cap ? cap - pos : 0, dims, "Float", 8, p->h5name, path);
    }
    XAPPEND("     </Geometry>\n");
    for (size_t k = 0; k < sizeof attr / sizeof attr[0]; k++) {
        if (!(p->fields & attr[k].field))
            continue;
        XAPPEND("     <Attribute Name=\"%s\" AttributeType=\"Scalar\" Center=\"Node\">\n", attr[k].name);
        snprintf(path, sizeof path, "/snapshots/%06" PRId64 "/%s", snap, attr[k].name);
        pos += xdmf_dataitem(buf + (pos < cap ? pos : cap), pos < cap ? cap - pos : 0, dims, attr[k].type, attr[k].prec,
                             p->h5name, path);
        XAPPEND("     </Attribute>\n");
    }
    if (p->fields & LAHAR_PFIELD_STRESS) { /* soil effective stress, n x 6 (xx, xy, xz, yy, yz, zz) */
        char dims6[40];
        snprintf(dims6, sizeof dims6, "%" PRId64 " 6", n);
        XAPPEND("     <Attribute Name=\"stress\" AttributeType=\"Tensor6\" Center=\"Node\">\n");
        snprintf(path, sizeof path, "/snapshots/%06" PRId64 "/stress", snap);
        pos += xdmf_dataitem(buf + (pos < cap ? pos : cap), pos < cap ? cap - pos : 0, dims6, "Float", 8, p->h5name, path);
        XAPPEND("     </Attribute>\n");
    }
    XAPPEND("    </Grid>\n");
    return pos;
}
