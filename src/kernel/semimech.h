/* The physics of the semi-mechanistic aggregation kernel (Chaudhury 2015,
 * ch. 4; docs/models.md), as pure functions of one particle or one pair, so
 * that tests can check them against hand-computed values. */
#ifndef GRANSIM_SEMIMECH_H
#define GRANSIM_SEMIMECH_H

/* Settings of the surface liquid and the Stokes criterion (SI units). */
typedef struct {
  double rho_solid, rho_liquid; /* kg/m3; the gas is massless */
  double viscosity;             /* binder viscosity mu, Pa s */
  double phi;                   /* Phi(theta) of the contact angle, eq. 4.4 */
  double pore_ratio;            /* S/(1 - S): pore liquid per unit pore gas at the critical saturation S */
  double surface_fraction;      /* x*: fraction of the pore liquid at the surface, eq. 4.1 */
  double asperity_fraction, asperity_max; /* h_a = min(fraction d, max) */
} gs_semimech_params;

/* What the kernel needs of one particle, from its solid, liquid and gas volumes. */
typedef struct {
  double d;    /* volume-equivalent diameter of s + l + g */
  double m;    /* mass */
  double wet;  /* A_wet / A_total, capped at 1 (0: no surface liquid) */
  double h0;   /* depth of the surface liquid, 1.5 V / A_wet (eq. 4.5) */
} gs_semimech_particle;

/* Phi(theta) = sin^3 / (2 - 3 cos + cos^3) of a contact angle in radians (eq. 4.4). */
double gs_semimech_phi(double theta);
/* Surface liquid of a granule with liquid l and pore gas g: what exceeds the
 * pores' hold at the critical saturation, plus x* of the liquid they hold. */
double gs_semimech_surface_liquid(const gs_semimech_params *p, double l, double g);
/* The droplet of surface liquid V as one spherical cap: wetted radius
 * (3 V Phi / pi)^(1/3) (eq. 4.3 with its cube root) and depth 1.5 V / A_wet. */
void gs_semimech_droplet(double V, double phi, double *radius, double *area, double *depth);
gs_semimech_particle gs_semimech_particle_of(const gs_semimech_params *p, double s, double l,
                                             double g);
/* Psi A of a pair (eqs. 4.6-4.9 without B0) at collision velocity u0. */
double gs_semimech_pair(const gs_semimech_params *p, const gs_semimech_particle *a,
                        const gs_semimech_particle *b, double u0);
/* The viscous Stokes number of a pair, 8 m~ u0 / (3 pi mu d~^2) (eq. 4.8). */
double gs_semimech_stokes(const gs_semimech_params *p, const gs_semimech_particle *a,
                          const gs_semimech_particle *b, double u0);
#endif
