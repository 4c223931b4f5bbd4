/* From the case to the solver: the parameters of the case's sph: section (lahar_sph_node_params)
 * and the particles of its blocks (lahar_sph_node_fill): the lattice inside each block and outside
 * the bodies, with the initial density from the block's pressure (rest, hydrostatic, an expression
 * or a file) through the inverse of the case's EOS. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "case_keys.h"
#include "sph_eos.h"
#include "sph_soil_model.h"
#include "sph_node_run.h"

/* Density of pressure p by the inverse of the case's EOS (sph_node/fluid/sph_eos.h). */
static double sph_node_eos_density(const lahar_case *c, double p)
{
    return sph_eos_get(c->sph.eos)->density(p, c->sph_density, c->sph.c0, c->sph.gamma);
}

/* Initial densities of the n particles pts of one block into rho. none: rest density. hydrostatic:
 * the density whose EOS pressure is p = rho0 |g| (h_free - s), s = -x.g/|g| the height along
 * gravity (the case's gravity only, not sph.body_force, which drives flows like Poiseuille's) and
 * h_free the block's free surface, half a spacing above its highest particle centre (the top face
 * of that particle's lattice cell: exact for a box with gravity along an axis). Assumes a block is
 * one connected water body whose free surface is its top; two blocks stacked along gravity each
 * get their own surface. Without gravity the densities stay at rest. */
static void sph_node_block_density(const lahar_case *c, const double (*pts)[3], int64_t n, double *rho)
{
    const vec3 g = v3_load(c->gravity);
    const double gmag = v3_norm(g);
    if (c->sph.initial_pressure != LAHAR_SPH_INITIAL_PRESSURE_HYDROSTATIC || !(gmag > 0.0)) {
        for (int64_t i = 0; i < n; i++)
            rho[i] = c->sph_density;
        return;
    }
    const vec3 up = v3_scale(g, -1.0 / gmag);
    double top = -HUGE_VAL;
    for (int64_t i = 0; i < n; i++) {
        const double s = v3_dot(v3_load(pts[i]), up);
        top = s > top ? s : top;
    }
    const double h_free = top + 0.5 * c->sph_dx;
    for (int64_t i = 0; i < n; i++)
        rho[i] = sph_node_eos_density(c, c->sph_density * gmag * (h_free - v3_dot(v3_load(pts[i]), up)));
}

/* Append the particles of every block at the density of sph.initial_pressure
 * (sph_node_block_density) with volume dx^D, mass rho dx^D (rho0 dx^D at rest density): a
 * particle's volume m / rho is its lattice cell, so a hydrostatic start is in equilibrium on the
 * lattice (with mass rho0 dx^D the volumes of the compressed lower rows would fall short of the
 * cells they fill, and the pressure gradient that holds them rises by up to rho g h / (rho0 c0^2)):
 * the lattice points of
 * lahar_case_block_lattice, i.e. inside the block and outside every body (a particle that starts
 * inside a body would be a crossing at step 0). 0, or -1 with the message in err (empty at the call):
 * out of memory, p without room, or an initial field that cannot be read. */
int sph_node_add_blocks(sph_particles *p, const lahar_case *c, char *err, size_t errlen)
{
    int64_t most = 0;
    for (int b = 0; b < c->nblock; b++) {
        int64_t n = lahar_case_block_lattice(c, b, NULL, 0);
        most = n > most ? n : most;
    }
    double(*pts)[3] = malloc((size_t)(most > 0 ? most : 1) * sizeof *pts);
    double *rho = malloc((size_t)(most > 0 ? most : 1) * sizeof *rho);
    double(*vel)[3] = malloc((size_t)(most > 0 ? most : 1) * sizeof *vel);
    if (!pts || !rho || !vel) {
        free(pts);
        free(rho);
        free(vel);
        snprintf(err, errlen, "out of memory for blocks of %lld particles", (long long)most);
        return -1;
    }
    const double vol = pow(c->sph_dx, c->dim);
    int rc = 0;
    for (int b = 0; b < c->nblock && !rc; b++) {
        int64_t n = lahar_case_block_lattice(c, b, pts, most);
        rc = n < 0 ? -1 : 0;
        /* soil blocks (sph_soil.h): at the rest density of their material, stress-free */
        const int soil = c->blocks[b].phase == SPH_SOIL_PHASE;
        const double rho_b = soil ? c->materials[c->blocks[b].material].density : c->sph_density;
        const double m = rho_b * vol;
        if (n > 0 && !soil)
            sph_node_block_density(c, (const double(*)[3])pts, n, rho);
        /* per-particle initial velocity and pressure (case keys velocity: / pressure: as
         * expressions): the pressure replaces the block's density by its inverse EOS */
        const lahar_particle_block *pb = &c->blocks[b];
        if (n < 0)
            snprintf(err, errlen, "cannot build the lattice of block '%s' (too many points, or out of memory)",
                     pb->name);
        if (n > 0 && !rc) {
            int has_p = 0;
            if (lahar_case_block_initial(pb, (const double(*)[3])pts, n, vel, rho, &has_p, err, errlen) != 0)
                rc = -1; /* the message is in err */
            else if (has_p)
                for (int64_t i = 0; i < n; i++)
                    rho[i] = sph_node_eos_density(c, rho[i]);
        }
        for (int64_t i = 0; i < n && !rc; i++)
            rc = sph_particles_add(p, pts[i], vel[i], soil ? m : rho[i] * vol, soil ? rho_b : rho[i],
                                   soil ? SPH_SOIL_PHASE : 0) < 0
                     ? -1
                     : 0;
        if (rc && !err[0])
            snprintf(err, errlen, "out of memory for the particles of block '%s'", pb->name);
    }
    free(pts);
    free(rho);
    free(vel);
    return rc;
}

int64_t sph_node_count(const lahar_case *c)
{
    int64_t total = 0;
    for (int b = 0; b < c->nblock; b++) {
        int64_t n = lahar_case_block_lattice(c, b, NULL, 0);
        if (n < 0)
            return -1;
        total += n;
    }
    return total;
}

int64_t lahar_sph_node_fill(sph_particles *p, const lahar_case *c)
{
    int64_t total = sph_node_count(c);
    if (total < 0 || sph_particles_init(p, total > 0 ? total : 1) != 0)
        return -1;
    char err[1400] = "";
    if (sph_node_add_blocks(p, c, err, sizeof err) != 0) {
        fprintf(stderr, "lahar-sph: %s\n", err);
        sph_particles_free(p);
        return -1;
    }
    return p->n;
}

int lahar_sph_node_params(const lahar_case *c, sph_params *prm, char *err, size_t errlen)
{
    const lahar_sph_options *o = &c->sph;
    memset(prm, 0, sizeof *prm);
    prm->opt = *o; /* every default already filled by the loader */
    prm->dim = c->dim;
    prm->dx = c->sph_dx;
    prm->rho0 = c->sph_density;
    for (int a = 0; a < 3; a++)
        prm->body_force[a] = c->gravity[a] + o->body_force[a];
    for (int b = 0; b < c->nblock; b++) /* one soil material per case (the loader checks) */
        if (c->blocks[b].phase == SPH_SOIL_PHASE && c->blocks[b].material >= 0 && c->blocks[b].material < c->nmaterial) {
            const lahar_material *mt = &c->materials[c->blocks[b].material];
            /* the constitutive model by its name in the key table (the case's choice) */
            const lahar_key *ck = lahar_key_find(lahar_key_section_find("materials.NAME"), "constitutive");
            int nchoice = 0;
            while (ck && ck->choices[nchoice])
                nchoice++;
            const sph_soil_model *model = mt->constitutive >= 0 && mt->constitutive < nchoice
                                              ? sph_soil_model_find(ck->choices[mt->constitutive])
                                              : NULL;
            if (!model) {
                snprintf(err, errlen, "materials.%s.constitutive: model %d is not one this SPH node has (%s); "
                         "update lahar-sph", mt->name, mt->constitutive,
                         mt->constitutive >= 0 && mt->constitutive < nchoice ? ck->choices[mt->constitutive] : "?");
                return -1;
            }
            prm->soil = 1;
            prm->soil_mat = (sph_soil_material){.density = mt->density, .young = mt->young, .poisson = mt->poisson,
                                                .phi = mt->friction_angle, .cohesion = mt->cohesion,
                                                .psi = mt->dilatancy, .kh = mt->permeability, .mu_phi = mt->friction,
                                                .damping = mt->damping, .av_alpha = mt->av_alpha,
                                                .av_beta = mt->av_beta, .rho_water = c->sph_density,
                                                .gravity = {c->gravity[0], c->gravity[1], c->gravity[2]},
                                                .g_ref = v3_norm(v3_load(c->gravity)) > 0.0
                                                             ? v3_norm(v3_load(c->gravity))
                                                             : 9.81,
                                                .model = model};
        }
    /* options of the case the solver core does not offer yet: refuse rather than ignore */
    if (o->halo > 0.0 && fabs(o->halo - 0.5 * c->sph_dx) > 1e-12 * c->sph_dx) {
        snprintf(err, errlen, "sph.halo: the coupling uses eps = dx/2 = %g m; another halo (%g m) is not implemented yet",
                 0.5 * c->sph_dx, o->halo);
        return -1;
    }
    const kernel_def *kd = kernel_find(o->kernel);
    if (o->kappa > 0.0 && kd && fabs(o->kappa - kd->kappa) > 1e-12) {
        snprintf(err, errlen, "sph.kappa: the coupling range is the kernel's support (%g h); %g h is not implemented yet",
                 kd->kappa, o->kappa);
        return -1;
    }
    return 0;
}
