/* The case format's keys, one table per section (case_keys.h). Units are SI. A doc line may end
 * in "; hint", which a range error repeats after the value it got. */
#include "case_keys.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define LO LAHAR_KEY_LO
#define HI LAHAR_KEY_HI
#define LOX (LAHAR_KEY_LO | LAHAR_KEY_LO_OPEN)
#define HIX (LAHAR_KEY_HI | LAHAR_KEY_HI_OPEN)
#define END {NULL, 0, 0, NULL, 0, 0, 0, NULL, NULL, NULL, NULL}

static const char *const bools[] = {"false", "true", NULL};

static const lahar_key top_keys[] = {
    {"dimensions", LAHAR_KEY_WHOLE, 1, NULL, LO | HI, 2, 3, NULL, "", "2 or 3; 2D scenes live in the x-y plane (masses and forces per unit thickness)", NULL},
    {"gravity", LAHAR_KEY_VECTOR, 0, "[0, 0, -9.81] (2D: [0, -9.81])", 0, 0, 0, NULL, "m/s^2", "acceleration of gravity", NULL},
    {"time", LAHAR_KEY_MAPPING, 1, NULL, 0, 0, 0, NULL, "", "duration, step bounds and output intervals", NULL},
    {"materials", LAHAR_KEY_MAPPING, 0, NULL, 0, 0, 0, NULL, "", "name -> material (required when there are bodies or soil)", NULL},
    {"dem", LAHAR_KEY_MAPPING, 0, NULL, 0, 0, 0, NULL, "", "the DEM engine and its step", NULL},
    {"bodies", LAHAR_KEY_LIST, 0, NULL, 0, 0, 0, NULL, "", "rigid bodies (sphero-polyhedra)", NULL},
    {"sph", LAHAR_KEY_MAPPING, 0, NULL, 0, 0, 0, NULL, "", "SPH water and soil and their coupling with the bodies", NULL},
    {"probes", LAHAR_KEY_LIST, 0, NULL, 0, 0, 0, NULL, "", "pressure probes and water-level gauges (OUT/gauges.h5)", NULL},
    {"stability", LAHAR_KEY_MAPPING, 0, NULL, 0, 0, 0, NULL, "", "instability checks that stop a run", NULL},
    {"checkpoint", LAHAR_KEY_MAPPING, 0, NULL, 0, 0, 0, NULL, "", "coordinated checkpoints for lahar resume (none without it)", NULL},
    {"output", LAHAR_KEY_MAPPING, 0, NULL, 0, 0, 0, NULL, "", "what the snapshots and streams hold", NULL},
    {"check", LAHAR_KEY_MAPPING, 0, NULL, 0, 0, 0, NULL, "", "the reference lahar check compares the run with", NULL},
    {"terrain", LAHAR_KEY_MAPPING, 0, NULL, 0, 0, 0, NULL, "", "a fixed DEM body from a 2D profile (points or CSV) or a 3D ESRI ASCII heightmap", NULL},
    {"trackers", LAHAR_KEY_LIST, 0, NULL, 0, 0, 0, NULL, "", "material points followed through the run (OUT/gauges.h5)", NULL},
    {"control_volumes", LAHAR_KEY_LIST, 0, NULL, 0, 0, 0, NULL, "", "boxes where kinetic energy, mass and mass flux are recorded (OUT/gauges.h5)", NULL},
    {"inlets", LAHAR_KEY_LIST, 0, NULL, 0, 0, 0, NULL, "", "open boundaries: sections where water enters with a hydrograph (cases/README.md)", NULL},
    {"outlets", LAHAR_KEY_LIST, 0, NULL, 0, 0, 0, NULL, "", "open boundaries: sections beyond which particles are removed and counted", NULL},
    {"domain", LAHAR_KEY_MAPPING, 0, NULL, 0, 0, 0, NULL, "", "open boundaries: particles outside this box are removed and counted", NULL},
    END};

static const lahar_key time_keys[] = {
    {"end", LAHAR_KEY_NUMBER, 1, NULL, LOX, 0, 0, NULL, "s", "simulated duration; give the simulated duration in seconds", NULL},
    {"dt_max", LAHAR_KEY_NUMBER, 0, "1e-3", LOX, 0, 0, NULL, "s", "upper bound of the coordinator step (the DEM node subcycles below it); it bounds the coordinator step, e.g. 1e-3", NULL},
    {"dt_min", LAHAR_KEY_NUMBER, 0, "1e-9", LOX, 0, 0, NULL, "s", "a step below this stops the run as a dt collapse (<= dt_max)", NULL},
    {"output_interval", LAHAR_KEY_NUMBER, 0, "end/100", LOX, 0, 0, NULL, "s", "snapshot interval (<= end)", NULL},
    {"forces_interval", LAHAR_KEY_NUMBER, 0, "0", LO, 0, 0, NULL, "s", "interval of the per-body force stream; 0 records every step", NULL},
    END};

static const char *const material_models[] = {"linear", "hertz", "soil", NULL};
/* the soil's constitutive models: the names of sph_node/soil/sph_soil_models.c, in lahar_material.constitutive's order */
static const char *const constitutive_models[] = {"drucker_prager", NULL};
static const lahar_key material_keys[] = {
    {"density", LAHAR_KEY_NUMBER, 1, NULL, LOX, 0, 0, NULL, "kg/m^3", "density (bodies: their mass properties come from it, soil: bulk density)", NULL},
    {"model", LAHAR_KEY_CHOICE, 0, "hertz", 0, 0, 0, material_models, "", "DEM contact law (linear, hertz) or an SPH soil (soil)", NULL},
    {"young", LAHAR_KEY_NUMBER, 0, NULL, LOX, 0, 0, NULL, "Pa", "Young's modulus (required for hertz and soil)", NULL},
    {"poisson", LAHAR_KEY_NUMBER, 0, "0.25 (soil: 0.3)", LO | HIX, 0, 0.5, NULL, "", "Poisson's ratio", NULL},
    {"kn", LAHAR_KEY_NUMBER, 0, NULL, LOX, 0, 0, NULL, "N/m", "normal stiffness (required for linear, N/m per m in 2D)", NULL},
    {"kt_ratio", LAHAR_KEY_NUMBER, 0, "2/7", LOX, 0, 0, NULL, "", "tangential / normal stiffness (DEM); 2/7 is the usual choice", NULL},
    {"restitution", LAHAR_KEY_NUMBER, 0, NULL, LOX | HI, 0, 1, NULL, "", "normal coefficient of restitution (required for DEM materials); 1 is elastic, small values are very dissipative", NULL},
    {"friction", LAHAR_KEY_NUMBER, 0, "soil: tan(friction_angle)", LO, 0, 0, NULL, "", "Coulomb friction coefficient (DEM: required, soil: the soil-DEM mu_phi); 0 is frictionless", NULL},
    {"constitutive", LAHAR_KEY_CHOICE, 0, "drucker_prager", 0, 0, 0, constitutive_models, "", "soil: the constitutive model (drucker_prager: Trujillo-Vela et al. 2020 eq. 6-7, sph_node/soil/)", NULL},
    {"friction_angle", LAHAR_KEY_NUMBER, 0, NULL, LO | HIX, 0, 90, NULL, "degrees", "soil: Mohr-Coulomb friction angle (required for soil); sands are about 30", NULL},
    {"cohesion", LAHAR_KEY_NUMBER, 0, "0", LO, 0, 0, NULL, "Pa", "soil: cohesion; 0 for a dry sand", NULL},
    {"dilatancy", LAHAR_KEY_NUMBER, 0, "0", LO, 0, 0, NULL, "degrees", "soil: dilatancy angle (<= friction_angle); 0 is usual", NULL},
    {"permeability", LAHAR_KEY_NUMBER, 0, "0", LO, 0, 0, NULL, "m/s", "soil: Darcy hydraulic conductivity k_h (seepage)", NULL},
    {"damping", LAHAR_KEY_NUMBER, 0, "0", LO, 0, 0, NULL, "1/s", "soil: velocity damping of the start-up; 0 = off, about the column's first frequency pi c/(2 H) damps its start-up in a few periods", NULL},
    {"av_alpha", LAHAR_KEY_NUMBER, 0, "0.1", LO, 0, 0, NULL, "", "soil: Monaghan's alpha; 0.1 by default, 1 in Trujillo-Vela et al.'s (2020) granular impact", NULL},
    {"av_beta", LAHAR_KEY_NUMBER, 0, "0", LO, 0, 0, NULL, "", "soil: Monaghan's beta; 0 by default", NULL},
    END};

static const lahar_key dem_keys[] = {
    {"engine", LAHAR_KEY_TEXT, 0, "spheropoly", 0, 0, 0, NULL, "", "name of the DEM engine (`lahar-dem --help` lists them)", NULL},
    {"dt_safety", LAHAR_KEY_NUMBER, 0, "0.02", LOX | HI, 0, 1, NULL, "", "fraction of the shortest contact period used as the DEM step; it is the fraction of the contact period used as the DEM step, 0.02 is safe", NULL},
    END};

static const lahar_key stability_keys[] = {
    {"density_band", LAHAR_KEY_VECTOR, 0, "[0.5, 2.0]", 0, 0, 0, NULL, "", "[lo, hi], 0 < lo < 1 < hi: the band of rho / rho0 every SPH particle must stay in", NULL},
    {"max_overlap", LAHAR_KEY_NUMBER, 0, "0.5", LOX | HI, 0, 1, NULL, "", "largest body-body overlap as a fraction of the smaller sweep radius; it is the largest body-body overlap as a fraction of the smaller sweep radius, e.g. 0.5", NULL},
    {"dt_collapse", LAHAR_KEY_NUMBER, 0, "1e-3", LO | HIX, 0, 1, NULL, "", "the run stops when the step falls below this fraction of the first step (0: only time.dt_min); the run stops when the step falls below this fraction of the first step (0: only time.dt_min), e.g. 1e-3", NULL},
    END};

static const lahar_key checkpoint_keys[] = {
    {"interval", LAHAR_KEY_NUMBER, 1, NULL, LOX, 0, 0, NULL, "s", "simulated time between checkpoints; a checkpoint is written at the first step ending at or after each multiple of it, e.g. 0.1", NULL},
    {"keep", LAHAR_KEY_WHOLE, 0, "2", LO | HI, 1, 1000, NULL, "", "how many of the newest checkpoints stay on disk; it is how many of the newest checkpoints stay on disk, e.g. 2", NULL},
    END};

static const char *const output_forces[] = {"none", "all", NULL};
static const lahar_key output_keys[] = {
    {"fields", LAHAR_KEY_LIST, 0, "all", 0, 0, 0, NULL, "", "particle fields of every snapshot: any of velocity, density, pressure, phase, id, stress (positions always)", NULL},
    {"forces", LAHAR_KEY_CHOICE, 0, "all", 0, 0, 0, output_forces, "", "all = write the per-body force stream forces.h5, none = do not", NULL},
    {"twins", LAHAR_KEY_BOOL, 0, "true", 0, 0, 0, bools, "", "write every snapshot through a hidden twin of particles.h5, bodies.h5 and contacts.h5, so that a node killed at any moment leaves them complete; the twins take as much room as the files while the run writes (false: in place, half the room, a killed node may leave a file unreadable)", NULL},
    END};

static const lahar_key check_keys[] = {
    {"reference", LAHAR_KEY_TEXT, 1, NULL, 0, 0, 0, NULL, "", "name of the reference (cases/README.md \"check: references\")", NULL},
    {"metrics", LAHAR_KEY_MAPPING, 0, NULL, 0, 0, 0, NULL, "", "metric name -> bound: passes when its value is <= bound (1 to 16 metrics)", NULL},
    END};

static const char *const probe_kinds[] = {"pressure", "level", NULL};
static const lahar_key probe_keys[] = {
    {"name", LAHAR_KEY_TEXT, 0, "probe<i>", 0, 0, 0, NULL, "", "unique name", NULL},
    {"kind", LAHAR_KEY_CHOICE, 0, "pressure", 0, 0, 0, probe_kinds, "", "pressure (a point) or level (water level on a vertical line)", NULL},
    {"position", LAHAR_KEY_VECTOR, 1, NULL, 0, 0, 0, NULL, "m", "the point (pressure) or the horizontal place of the line (level: [x] in 2D, [x, y] in 3D)", NULL},
    {"body", LAHAR_KEY_TEXT, 0, NULL, 0, 0, 0, NULL, "", "pressure probes: a body's name: the probe is a sensor on its surface", NULL},
    {"size", LAHAR_KEY_NUMBER, 0, "0", LO, 0, 0, NULL, "m", "pressure probes on a body: sensor diameter (0 = a point); the sensor's diameter in m, 0 for a point", NULL},
    {"rate", LAHAR_KEY_NUMBER, 0, "0", LO, 0, 0, NULL, "Hz", "samples per second (0 = every step); samples per second, 0 or absent = every step", NULL},
    END};

static const lahar_key inlet_keys[] = {
    {"name", LAHAR_KEY_TEXT, 0, "inlet<i>", 0, 0, 0, NULL, "", "name (messages)", NULL},
    {"position", LAHAR_KEY_VECTOR, 1, NULL, 0, 0, 0, NULL, "m", "one end of the line (2D) / a corner of the rectangle (3D)", NULL},
    {"edge", LAHAR_KEY_VECTOR, 1, NULL, 0, 0, 0, NULL, "m", "the section is position + a edge (+ b edge2), a, b in [0, 1]", NULL},
    {"edge2", LAHAR_KEY_VECTOR, 0, NULL, 0, 0, 0, NULL, "m", "3D (required there): the rectangle's second edge, perpendicular to edge", NULL},
    {"normal", LAHAR_KEY_VECTOR, 1, NULL, 0, 0, 0, NULL, "", "inward normal, perpendicular to the edges (normalised)", NULL},
    {"level", LAHAR_KEY_NUMBER, 0, NULL, LOX, 0, 0, NULL, "m", "water depth above the section's lowest point along gravity (or level_hydrograph)", NULL},
    {"level_hydrograph", LAHAR_KEY_TEXT, 0, NULL, 0, 0, 0, NULL, "", "CSV t,h: the level h(t) instead of level (path relative to the case file)", NULL},
    {"velocity", LAHAR_KEY_NUMBER, 0, NULL, LO, 0, 0, NULL, "m/s", "a constant inflow velocity (one of velocity, gumbel, hydrograph); the inflow along the inward normal", NULL},
    {"gumbel", LAHAR_KEY_VECTOR, 0, NULL, 0, 0, 0, NULL, "", "[a_G (m), beta_G (s), mu_G (s)]: u of Trujillo-Vela et al. 2020, eq. 36", NULL},
    {"hydrograph", LAHAR_KEY_TEXT, 0, NULL, 0, 0, 0, NULL, "", "CSV t,u (m/s) or t,Q (m^2/s in 2D, m^3/s in 3D), relative to the case file", NULL},
    {"start", LAHAR_KEY_NUMBER, 0, "0", 0, 0, 0, NULL, "s", "the inflow acts from start", NULL},
    {"end", LAHAR_KEY_NUMBER, 0, "forever", 0, 0, 0, NULL, "s", "... until end (u = 0 outside [start, end))", NULL},
    {"layers", LAHAR_KEY_WHOLE, 0, "support/dx", LO | HI, 1, 64, NULL, "", "buffer rows behind the section", NULL},
    {"max_particles", LAHAR_KEY_WHOLE, 0, "estimate", LO | HI, 1, 1e12, NULL, "", "most particles the inlet may create (default: from the hydrograph + 10 %)", NULL},
    END};

static const lahar_key outlet_keys[] = {
    {"name", LAHAR_KEY_TEXT, 0, "outlet<i>", 0, 0, 0, NULL, "", "name (messages)", NULL},
    {"position", LAHAR_KEY_VECTOR, 1, NULL, 0, 0, 0, NULL, "m", "one end of the line (2D) / a corner of the rectangle (3D)", NULL},
    {"edge", LAHAR_KEY_VECTOR, 1, NULL, 0, 0, 0, NULL, "m", "the section is position + a edge (+ b edge2), a, b in [0, 1]", NULL},
    {"edge2", LAHAR_KEY_VECTOR, 0, NULL, 0, 0, 0, NULL, "m", "3D (required there): the rectangle's second edge", NULL},
    {"normal", LAHAR_KEY_VECTOR, 1, NULL, 0, 0, 0, NULL, "", "outward normal, perpendicular to the edges (normalised)", NULL},
    {"depth", LAHAR_KEY_NUMBER, 0, "unlimited", LOX, 0, 0, NULL, "m", "how far beyond the section particles are removed; how far beyond the section, m", NULL},
    END};

static const lahar_key domain_keys[] = {
    {"lo", LAHAR_KEY_VECTOR, 1, NULL, 0, 0, 0, NULL, "m", "lower corner of the box", NULL},
    {"hi", LAHAR_KEY_VECTOR, 1, NULL, 0, 0, 0, NULL, "m", "upper corner (> lo on every axis)", NULL},
    END};

static const char *const kernels[] = {"cubic", "quintic", "wendland2", NULL};
static const char *const eos_names[] = {"linear", "tait", NULL};
static const char *const wall_viscous_names[] = {"halfspace", "paper", NULL};
static const char *const initial_pressure_names[] = {"none", "hydrostatic", NULL};
static const char *const wall_pressure_names[] = {"penalty", "ghost", NULL};
static const char *const penalty_stiffness_names[] = {"step", "acoustic", NULL};
static const char *const scheme_names[] = {"delta", "riemann", NULL};
static const lahar_key sph_keys[] = {
    {"dx", LAHAR_KEY_NUMBER, 1, NULL, LOX, 0, 0, NULL, "m", "particle spacing; it is the particle spacing", NULL},
    {"density", LAHAR_KEY_NUMBER, 0, "1000", LOX, 0, 0, NULL, "kg/m^3", "rest density rho0 of the water", NULL},
    {"kernel", LAHAR_KEY_CHOICE, 0, "cubic", 0, 0, 0, kernels, "", "smoothing kernel: cubic (support 2h), quintic (Morris 1997, 3h), wendland2 (Wendland C2, 2h)", NULL},
    {"h_over_dx", LAHAR_KEY_NUMBER, 0, "1.3", LO | HI, 0.5, 4, NULL, "", "smoothing length h = h_over_dx dx; h = h_over_dx dx, 1.0-1.5 is usual", NULL},
    {"c0", LAHAR_KEY_NUMBER, 0, "10 U_ref", LOX, 0, 0, NULL, "m/s", "numerical speed of sound (U_ref: cases/README.md); about 10 x the largest expected flow speed", NULL},
    {"eos", LAHAR_KEY_CHOICE, 0, "linear", 0, 0, 0, eos_names, "", "equation of state: linear p = c0^2 (rho - rho0) (Trujillo-Vela et al. 2020 eq. 3) or tait (Canelas et al. 2015 eq. 19)", NULL},
    {"gamma", LAHAR_KEY_NUMBER, 0, "7", LO, 1, 0, NULL, "", "Tait exponent (only with eos: tait); 7 for water", NULL},
    {"viscosity", LAHAR_KEY_NUMBER, 0, "1e-3", LO, 0, 0, NULL, "Pa s", "dynamic viscosity; water is 1e-3", NULL},
    {"alpha", LAHAR_KEY_NUMBER, 0, "0", LO | HI, 0, 1, NULL, "", "Monaghan artificial viscosity; 0.01-0.1 is usual, 0 = off", NULL},
    {"delta", LAHAR_KEY_NUMBER, 0, "0.1", LO | HI, 0, 1, NULL, "", "delta-SPH density diffusion; 0.1 is usual, 0 = off", NULL},
    {"cfl", LAHAR_KEY_NUMBER, 0, "0.25", LOX | HI, 0, 1, NULL, "", "acoustic step factor: dt <= cfl h / (c0 + |v|max) (Canelas et al. 2015 eq. 20)", NULL},
    {"cfl_force", LAHAR_KEY_NUMBER, 0, "0.25", LOX | HI, 0, 1, NULL, "", "force step factor: dt <= cfl_force sqrt(h / |a|max)", NULL},
    {"cfl_visc", LAHAR_KEY_NUMBER, 0, "0.125", LOX | HI, 0, 1, NULL, "", "viscous step factor: dt <= cfl_visc h^2 / nu", NULL},
    {"body_force", LAHAR_KEY_VECTOR, 0, "0", 0, 0, 0, NULL, "m/s^2", "acceleration of the fluid only, added to gravity (drives periodic flows)", NULL},
    {"periodic", LAHAR_KEY_MAPPING, 0, "none", 0, 0, 0, NULL, "", "{x: [lo, hi], y: ..., z: ...}: periodic axes, each a whole number of dx holding 3 kernel supports", NULL},
    {"shepard_interval", LAHAR_KEY_WHOLE, 0, "0", LO | HI, 0, 1e6, NULL, "", "steps between Shepard density filters (Canelas et al. 2015 eq. 5); 0 = off", NULL},
    {"sps", LAHAR_KEY_BOOL, 0, "false", 0, 0, 0, bools, "", "Smagorinsky SPS turbulence (Canelas et al. 2015 eq. 10-11)", NULL},
    {"sps_cs", LAHAR_KEY_NUMBER, 0, "0.12", LOX | HIX, 0, 1, NULL, "", "Smagorinsky constant of sps: true; 0.12 is usual", NULL},
    {"halo", LAHAR_KEY_NUMBER, 0, "dx/2", 0, 0, 0, NULL, "m", "coupling halo: a particle closer than it to a body is pushed back (Trujillo-Vela et al. 2020 eq. 14)", NULL},
    {"kappa", LAHAR_KEY_NUMBER, 0, "the kernel's support (2, quintic 3)", LOX | HI, 0, 4, NULL, "", "coupling range in h: particles within kappa h of a body feel it", NULL},
    {"wall_viscous", LAHAR_KEY_CHOICE, 0, "halfspace", 0, 0, 0, wall_viscous_names, "", "wall shear of the virtual particle: halfspace (Morris operator over the half-space) or paper (Trujillo-Vela et al. 2020 eq. 17)", NULL},
    {"initial_pressure", LAHAR_KEY_CHOICE, 0, "none", 0, 0, 0, initial_pressure_names, "", "none: particles start at rho0; hydrostatic: at the density of rho |g| depth, per block", NULL},
    {"wall_pressure", LAHAR_KEY_CHOICE, 0, "penalty", 0, 0, 0, wall_pressure_names, "", "penalty (Trujillo-Vela et al. 2020 eq. 15) or ghost: plus ghost layers behind the surface (Adami et al. 2012)", NULL},
    {"penalty_stiffness", LAHAR_KEY_CHOICE, 0, "step", 0, 0, 0, penalty_stiffness_names, "", "K_n = 0.1 m_min / dt^2 with the step's dt (step) or the acoustic step (acoustic; use with wall_pressure: ghost)", NULL},
    {"soil_wall_stress", LAHAR_KEY_CHOICE, 0, "penalty", 0, 0, 0, wall_pressure_names, "", "soil on bodies: penalty (eq. 15 + friction spring) or ghost (ghost layers carry the soil stress; recommended)", NULL},
    {"shifting", LAHAR_KEY_NUMBER, 0, "0", LO | HI, 0, 0.5, NULL, "", "particle shifting coefficient A (Lind et al. 2012; water-only flows without a free surface); 0.01 is usual, 0 = off (particle shifting: confined flows only, lahar detects no free surface)", NULL},
    {"shifting_density", LAHAR_KEY_BOOL, 0, "false", 0, 0, 0, bools, "", "the shift also changes the density as the continuity equation would (keeps a closed box's volume)", NULL},
    {"background_pressure", LAHAR_KEY_NUMBER, 0, "0 (transport_velocity: rho0 c0^2)", LO, 0, 0, NULL, "Pa", "background pressure p_b (Adami et al. 2013)", NULL},
    {"transport_velocity", LAHAR_KEY_BOOL, 0, "false", 0, 0, 0, bools, "", "transport-velocity formulation (Adami et al. 2013): fully periodic water-only flows", NULL},
    {"body_layers", LAHAR_KEY_WHOLE, 0, "0", LO | HI, 0, 8, NULL, "", "particles within N dx of sphere/disc bodies start on N concentric layers; 0 = the plain lattice, 2-3 usual", NULL},
    {"scheme", LAHAR_KEY_CHOICE, 0, "delta", 0, 0, 0, scheme_names, "", "delta: delta-SPH + artificial viscosity; riemann: the low-dissipation Riemann solver of Zhang, Hu & Adams 2017 (alpha and delta then 0)", NULL},
    {"riemann_limiter", LAHAR_KEY_NUMBER, 0, "3", LO | HI, 0, 100, NULL, "", "eta of the Riemann scheme's dissipation limiter beta = min(eta max(dU, 0), c0); 3 as in Zhang et al. 2017 (low dissipation: the start-up waves of water at rest take about three times as long to settle), 0 = no limiter (the full acoustic dissipation: a tank at rest settles as fast as with delta-SPH, impacts are braked)", NULL},
    {"blocks", LAHAR_KEY_LIST, 1, NULL, 0, 0, 0, NULL, "", "regions filled with particles (non-empty)", NULL},
    END};

static const lahar_key periodic_keys[] = {
    {"x", LAHAR_KEY_VECTOR, 0, NULL, 0, 0, 0, NULL, "m", "[lo, hi): the period along x", NULL},
    {"y", LAHAR_KEY_VECTOR, 0, NULL, 0, 0, 0, NULL, "m", "[lo, hi): the period along y", NULL},
    {"z", LAHAR_KEY_VECTOR, 0, NULL, 0, 0, 0, NULL, "m", "[lo, hi): the period along z (3D)", NULL},
    END};

static const char *const phases[] = {"water", "soil", NULL};
static const lahar_key block_keys[] = {
    {"name", LAHAR_KEY_TEXT, 0, "block<i>", 0, 0, 0, NULL, "", "unique name", NULL},
    {"box", LAHAR_KEY_MAPPING, 0, NULL, 0, 0, 0, NULL, "m", "{lo: [..], hi: [..]} corners (one of box, polygon, stl)", NULL},
    {"polygon", LAHAR_KEY_LIST, 0, NULL, 0, 0, 0, NULL, "m", "2D: [[x, y], ...] a simple polygon, convex or not", NULL},
    {"stl", LAHAR_KEY_MAPPING, 0, NULL, 0, 0, 0, NULL, "", "3D: {file, scale: 1, position: [0, 0, 0]} a closed watertight surface", NULL},
    {"velocity", LAHAR_KEY_VECTOR, 0, "0", 0, 0, 0, NULL, "m/s", "initial velocity; each component a number or an expression in x, y, z", NULL},
    {"pressure", LAHAR_KEY_TEXT, 0, NULL, 0, 0, 0, NULL, "Pa", "water: initial pressure, a number or an expression in x, y, z", NULL},
    {"initial", LAHAR_KEY_MAPPING, 0, NULL, 0, 0, 0, NULL, "", "{file: F.h5}: per-particle vx, vy (, vz), pressure in lattice order", NULL},
    {"phase", LAHAR_KEY_CHOICE, 0, "water", 0, 0, 0, phases, "", "water or soil", NULL},
    {"material", LAHAR_KEY_TEXT, 0, NULL, 0, 0, 0, NULL, "", "soil blocks: a materials entry with model: soil (required for soil)", NULL},
    {"between", LAHAR_KEY_MAPPING, 0, NULL, 0, 0, 0, NULL, "", "{top: ...}: the region between the terrain and an upper surface (2D polyline, 3D grid file)", NULL},
    END};

static const char *const shapes[] = {"sphere", "disc", "box", "segment", "polyline", "polygon", "polyhedron",
                                     "plane", "stl", NULL};
static const char *const motions[] = {"free", "fixed", "prescribed", NULL};
/* the shapes a shape-specific key of bodies[] belongs to */
static const char *const box_plane[] = {"box", "plane", NULL};
static const char *const vertex_shapes[] = {"segment", "polyline", "polygon", "polyhedron", NULL};
static const char *const polyhedron_only[] = {"polyhedron", NULL};
static const char *const polyline_only[] = {"polyline", NULL};
static const char *const plane_only[] = {"plane", NULL};
static const char *const stl_only[] = {"stl", NULL};
static const lahar_key body_keys[] = {
    {"name", LAHAR_KEY_TEXT, 0, "body<i>", 0, 0, 0, NULL, "", "unique name", NULL},
    {"shape", LAHAR_KEY_CHOICE, 1, NULL, 0, 0, 0, shapes, "", "sphere, box, segment, polyhedron, plane, stl (3D); disc, box, segment, polygon, polyline (2D)", NULL},
    {"material", LAHAR_KEY_TEXT, 1, NULL, 0, 0, 0, NULL, "", "a name from materials", NULL},
    {"motion", LAHAR_KEY_CHOICE, 0, "free", 0, 0, 0, motions, "", "free, fixed (a wall) or prescribed (moves with its given velocities)", NULL},
    {"radius", LAHAR_KEY_NUMBER, 1, NULL, LOX, 0, 0, NULL, "m", "sphere/disc radius, otherwise the sweep (rounding) radius of the core", NULL},
    {"position", LAHAR_KEY_VECTOR, 0, "0", 0, 0, 0, NULL, "m", "where the shape's local origin goes", NULL},
    {"orientation", LAHAR_KEY_MAPPING, 0, "none", 0, 0, 0, NULL, "", "{axis: [x, y, z], angle_deg: a} (2D: angle_deg only, about +z)", NULL},
    {"velocity", LAHAR_KEY_VECTOR, 0, "0", 0, 0, 0, NULL, "m/s", "initial velocity (not for fixed bodies)", NULL},
    {"angular_velocity", LAHAR_KEY_VECTOR, 0, "0", 0, 0, 0, NULL, "rad/s", "world frame (2D: one number about +z)", NULL},
    {"record_contacts", LAHAR_KEY_BOOL, 0, "false", 0, 0, 0, bools, "", "the SPH node writes every fluid contact point on this body (contacts.h5)", NULL},
    {"size", LAHAR_KEY_VECTOR, 0, NULL, 0, 0, 0, NULL, "m", "box: outer size [sx, sy(, sz)] (every side > 2 radius); plane: [a, b]", box_plane},
    {"vertices", LAHAR_KEY_LIST, 0, NULL, 0, 0, 0, NULL, "m", "segment, polyline, polygon, polyhedron: [[x, y(, z)], ...] in the local frame", vertex_shapes},
    {"faces", LAHAR_KEY_LIST, 0, "the convex hull", 0, 0, 0, NULL, "", "polyhedron: [[i, j, k, ...], ...] counter-clockwise seen from outside", polyhedron_only},
    {"closed", LAHAR_KEY_BOOL, 0, "false", 0, 0, 0, bools, "", "polyline: join the last point to the first", polyline_only},
    {"normal", LAHAR_KEY_VECTOR, 0, NULL, 0, 0, 0, NULL, "", "plane: outward normal (the side bodies stay on)", plane_only},
    {"file", LAHAR_KEY_TEXT, 0, NULL, 0, 0, 0, NULL, "", "stl: ASCII or binary STL path, relative to the case file", stl_only},
    {"scale", LAHAR_KEY_NUMBER, 0, "1", LOX, 0, 0, NULL, "", "stl: factor on the file's coordinates (0.001 for mm)", stl_only},
    END};


static const lahar_key terrain_keys[] = {
    {"name", LAHAR_KEY_TEXT, 0, "terrain", 0, 0, 0, NULL, "", "the body's name", NULL},
    {"file", LAHAR_KEY_TEXT, 0, NULL, 0, 0, 0, NULL, "", "a CSV of x,y (2D) or an ESRI ASCII grid, .asc (3D), relative to the case file (or points)", NULL},
    {"points", LAHAR_KEY_LIST, 0, NULL, 0, 0, 0, NULL, "m", "2D: [[x, y], ...] the profile, instead of file", NULL},
    {"material", LAHAR_KEY_TEXT, 1, NULL, 0, 0, 0, NULL, "", "a DEM material (its friction is the bed's mu_phi against soil)", NULL},
    {"radius", LAHAR_KEY_NUMBER, 1, NULL, LOX, 0, 0, NULL, "m", "sweep radius of the surface (it lies radius above the points)", NULL},
    END};

static const char *const cv_axes[] = {"x", "y", "z", NULL};
static const lahar_key tracker_keys[] = {
    {"name", LAHAR_KEY_TEXT, 0, "tracker<i>", 0, 0, 0, NULL, "", "unique name", NULL},
    {"position", LAHAR_KEY_VECTOR, 1, NULL, 0, 0, 0, NULL, "m", "the particle nearest this point at t = 0 is followed", NULL},
    {"rate", LAHAR_KEY_NUMBER, 0, "0", LO, 0, 0, NULL, "Hz", "samples per second (0 = every step); samples per second, 0 or absent = every step", NULL},
    END};

static const lahar_key control_volume_keys[] = {
    {"name", LAHAR_KEY_TEXT, 0, "cv<i>", 0, 0, 0, NULL, "", "unique name", NULL},
    {"box", LAHAR_KEY_MAPPING, 1, NULL, 0, 0, 0, NULL, "m", "{lo: [..], hi: [..]}: kinetic energy (Trujillo-Vela et al. 2020 eq. 39) and mass inside", NULL},
    {"axis", LAHAR_KEY_CHOICE, 0, "x", 0, 0, 0, cv_axes, "", "direction of the mass flux recorded through the box", NULL},
    {"rate", LAHAR_KEY_NUMBER, 0, "0", LO, 0, 0, NULL, "Hz", "samples per second (0 = every step); samples per second, 0 or absent = every step", NULL},
    END};

static const lahar_key_section sections[] = {
    {"", "the top level of a case file", top_keys},
    {"time", "duration, step bounds and output intervals (required)", time_keys},
    {"materials.NAME", "a material: DEM contact properties (linear, hertz) or an SPH soil (soil)", material_keys},
    {"dem", "the DEM engine (optional)", dem_keys},
    {"bodies[]", "a rigid body: a core swept by a sphere of `radius` (shape-specific keys at the end)", body_keys},
    {"sph", "weakly compressible SPH and its coupling with the bodies (Trujillo-Vela et al. 2020 sec. 2.1, 4; Canelas et al. 2015 sec. 3)", sph_keys},
    {"sph.periodic", "periodic axes of the fluid", periodic_keys},
    {"sph.blocks[]", "a region filled with particles on the lattice lo + (i + 1/2) dx", block_keys},
    {"terrain", "the ground as one fixed DEM body (optional)", terrain_keys},
    {"trackers[]", "a material point followed through the run", tracker_keys},
    {"control_volumes[]", "a box where energies, mass and mass flux are recorded", control_volume_keys},
    {"probes[]", "a pressure probe or a water-level gauge, sampled into OUT/gauges.h5", probe_keys},
    {"stability", "the instability checks (optional)", stability_keys},
    {"checkpoint", "coordinated checkpoints (optional; lahar resume)", checkpoint_keys},
    {"output", "what is written (optional)", output_keys},
    {"check", "the reference of lahar check (optional)", check_keys},
    {"inlets[]", "an inlet: water enters through the section with a hydrograph (optional; cases/README.md \"Open boundaries\")", inlet_keys},
    {"outlets[]", "an outlet: particles beyond the section are removed and counted (optional)", outlet_keys},
    {"domain", "particles outside the box are removed and counted (optional)", domain_keys},
};

const lahar_key_section *lahar_key_sections(int *count)
{
    *count = (int)(sizeof sections / sizeof sections[0]);
    return sections;
}

int lahar_key_applies(const lahar_key *k, const char *variant)
{
    if (!k->only)
        return 1;
    for (int i = 0; k->only[i]; i++)
        if (strcmp(k->only[i], variant) == 0)
            return 1;
    return 0;
}

const lahar_key_section *lahar_key_section_find(const char *path)
{
    for (size_t i = 0; i < sizeof sections / sizeof sections[0]; i++)
        if (strcmp(sections[i].path, path) == 0)
            return &sections[i];
    return NULL;
}

const lahar_key *lahar_key_find(const lahar_key_section *s, const char *name)
{
    if (!s)
        return NULL;
    for (const lahar_key *k = s->keys; k->name; k++)
        if (strcmp(k->name, name) == 0)
            return k;
    return NULL;
}

double lahar_key_default(const lahar_key *k)
{
    if (!k || !k->def)
        return NAN;
    char *end = NULL;
    double v = strtod(k->def, &end);
    return end != k->def && *end == '\0' ? v : NAN;
}

int lahar_key_in_range(const lahar_key *k, double v)
{
    if (!isfinite(v))
        return 0;
    if (k->type == LAHAR_KEY_WHOLE && v != floor(v))
        return 0;
    if (k->range & LAHAR_KEY_LO && (k->range & LAHAR_KEY_LO_OPEN ? !(v > k->lo) : !(v >= k->lo)))
        return 0;
    if (k->range & LAHAR_KEY_HI && (k->range & LAHAR_KEY_HI_OPEN ? !(v < k->hi) : !(v <= k->hi)))
        return 0;
    return 1;
}

/* "in (0, 1]", "> 0", ">= 1", "a whole number from 1 to 1000" */
static void range_text(const lahar_key *k, char *out, size_t n)
{
    const int lo = k->range & LAHAR_KEY_LO, hi = k->range & LAHAR_KEY_HI;
    const int lox = k->range & LAHAR_KEY_LO_OPEN, hix = k->range & LAHAR_KEY_HI_OPEN;
    if (k->type == LAHAR_KEY_WHOLE && lo && hi)
        snprintf(out, n, "a whole number from %g to %g", k->lo, k->hi);
    else if (k->type == LAHAR_KEY_WHOLE && lo)
        snprintf(out, n, "a whole number >= %g", k->lo);
    else if (lo && hi)
        snprintf(out, n, "in %c%g, %g%c", lox ? '(' : '[', k->lo, k->hi, hix ? ')' : ']');
    else if (lo)
        snprintf(out, n, "%s %g", lox ? ">" : ">=", k->lo);
    else if (hi)
        snprintf(out, n, "%s %g", hix ? "<" : "<=", k->hi);
    else
        snprintf(out, n, "%s", k->type == LAHAR_KEY_WHOLE ? "a whole number" : "finite");
}

/* Where the doc's "; hint" tail starts: the hint completes the range error of a number
 * (lahar_key_range_error), so only numbers have one, and it is the first "; " outside parentheses
 * (a "; " inside "(...)" belongs to the description). NULL: the whole doc is the description. */
static const char *doc_hint(const lahar_key *k)
{
    if (!k->doc || (k->type != LAHAR_KEY_NUMBER && k->type != LAHAR_KEY_WHOLE))
        return NULL;
    int depth = 0;
    for (const char *p = k->doc; *p; p++) {
        if (*p == '(')
            depth++;
        else if (*p == ')' && depth > 0)
            depth--;
        else if (*p == ';' && p[1] == ' ' && depth == 0)
            return p;
    }
    return NULL;
}

void lahar_key_range_error(const lahar_key *k, double v, char *out, size_t n)
{
    char rt[96];
    range_text(k, rt, sizeof rt);
    const char *hint = doc_hint(k);
    snprintf(out, n, "must be %s%s%s (got %g)%s%s", rt, k->unit && k->unit[0] ? " " : "", k->unit ? k->unit : "", v,
             hint ? "; " : "", hint ? hint + 2 : "");
}

static const char *type_name(const lahar_key *k)
{
    switch (k->type) {
    case LAHAR_KEY_NUMBER: return "number";
    case LAHAR_KEY_WHOLE: return "whole";
    case LAHAR_KEY_BOOL: return "bool";
    case LAHAR_KEY_CHOICE: return "choice";
    case LAHAR_KEY_VECTOR: return "vector";
    case LAHAR_KEY_TEXT: return "text";
    case LAHAR_KEY_MAPPING: return "mapping";
    case LAHAR_KEY_LIST: return "list";
    }
    return "?";
}

/* The doc without its "; hint" tail. */
static int doc_len(const lahar_key *k)
{
    const char *hint = doc_hint(k);
    return hint ? (int)(hint - k->doc) : (int)strlen(k->doc);
}

static void allowed_text(const lahar_key *k, char *out, size_t n)
{
    out[0] = '\0';
    if (k->choices) {
        size_t used = 0;
        for (int i = 0; k->choices[i] && used < n; i++)
            used += (size_t)snprintf(out + used, n - used, "%s%s", i ? " | " : "", k->choices[i]);
    } else if (k->range || k->type == LAHAR_KEY_WHOLE) {
        range_text(k, out, n);
    }
}

static void print_section(FILE *f, const lahar_key_section *s)
{
    fprintf(f, "%s: %s\n", s->path[0] ? s->path : "(top level)", s->doc);
    fprintf(f, "  %-20s %-8s %-10s %-24s %-26s %s\n", "key", "type", "unit", "default", "allowed", "what");
    for (const lahar_key *k = s->keys; k->name; k++) {
        char allowed[128];
        allowed_text(k, allowed, sizeof allowed);
        fprintf(f, "  %-20s %-8s %-10s %-24s %-26s %.*s\n", k->name, type_name(k), k->unit[0] ? k->unit : "-",
                k->required ? "(required)" : (k->def ? k->def : "-"), allowed[0] ? allowed : "-", doc_len(k), k->doc);
    }
}

int lahar_keys_print(FILE *f, const char *section)
{
    int n = (int)(sizeof sections / sizeof sections[0]);
    if (section) {
        /* as written in the table, or as written in a case: bodies for bodies[], materials for
         * materials.NAME, sph.blocks for sph.blocks[] */
        const lahar_key_section *s = lahar_key_section_find(section);
        for (int i = 0; i < n && !s; i++) {
            size_t len = strlen(section), plen = strlen(sections[i].path);
            if (len && plen > len && strncmp(sections[i].path, section, len) == 0 &&
                (strcmp(sections[i].path + len, "[]") == 0 || strcmp(sections[i].path + len, ".NAME") == 0))
                s = &sections[i];
        }
        if (!s) {
            fprintf(stderr, "lahar keys: unknown section '%s'; the sections are:", section);
            for (int i = 0; i < n; i++)
                fprintf(stderr, " %s", sections[i].path[0] ? sections[i].path : "''");
            fprintf(stderr, "\n");
            return -1;
        }
        print_section(f, s);
        return 0;
    }
    for (int i = 0; i < n; i++) {
        print_section(f, &sections[i]);
        if (i + 1 < n)
            fprintf(f, "\n");
    }
    return 0;
}

void lahar_keys_print_yaml(FILE *f)
{
    fprintf(f, "# lahar case reference: every key of the case format with its unit, default and allowed\n"
               "# values, written by `lahar keys --yaml` from common/io/case_keys.c (do not edit by hand: a\n"
               "# test fails when this file differs from the table). Every line is a comment; copy what you\n"
               "# need into a case. Units are SI; (required) marks keys without a default.\n");
    int n = (int)(sizeof sections / sizeof sections[0]);
    for (int i = 0; i < n; i++) {
        const lahar_key_section *s = &sections[i];
        /* indentation from the path: "sph.blocks[]" -> 2 levels */
        int depth = 0;
        for (const char *p = s->path; *p; p++)
            depth += *p == '.';
        depth += s->path[0] ? 1 : 0;
        fprintf(f, "#\n# --- %s: %s\n", s->path[0] ? s->path : "top level", s->doc);
        if (s->path[0]) {
            const char *last = strrchr(s->path, '.');
            last = last ? last + 1 : s->path;
            fprintf(f, "# %*s%.*s:%s\n", 2 * (depth - 1), "", (int)strcspn(last, "["), last,
                    strchr(last, '[') ? "   # a list; each item:" : "");
        }
        for (const lahar_key *k = s->keys; k->name; k++) {
            char allowed[128], entry[256];
            allowed_text(k, allowed, sizeof allowed);
            snprintf(entry, sizeof entry, "%*s%s: %s", 2 * depth, "", k->name,
                     k->required ? "(required)" : (k->def ? k->def : "(none)"));
            fprintf(f, "# %-44s # %s%s%s%s%.*s\n", entry, k->unit[0] ? k->unit : "", k->unit[0] ? "; " : "",
                    allowed[0] ? allowed : "", allowed[0] ? "; " : "", doc_len(k), k->doc);
        }
    }
}
