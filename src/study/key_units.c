/* The SI unit of a case key a study varies (study_internal.h), from the
 * table "Units of the keys" in docs/case-files.md: a key's unit follows
 * from its last name (`mechanisms.0.kernel.rtol` -> rtol).  Names whose unit
 * depends on the model (beta0, s0, a mechanism's `rate`, `min`/`max` of a
 * volume or a diameter) are left out: their columns say "case", the unit
 * the case file gives the key (docs/studies.md). */
#include <ctype.h>
#include <stdio.h>
#include <string.h>

#include "study/study_internal.h"

typedef struct {
  const char *name, *unit;
} key_unit;

static const key_unit table[] = {
    /* time */
    {"start", "s"}, {"end", "s"}, {"times", "s"}, {"first", "s"}, {"initial_step", "s"},
    {"min_step", "s"}, {"max_step", "s"}, {"residence_time", "s"}, {"time_step", "s"},
    {"duration", "s"}, {"every", "s"}, {"vtk_every", "s"}, {"sample_every", "s"},
    {"max_time", "s"}, {"collect", "s"},
    /* volume of a constituent or particle */
    {"min_volume", "m^3"}, {"max_volume", "m^3"}, {"fines_max", "m^3"}, {"pivots", "m^3"},
    /* length */
    {"droplet_diameter", "m"}, {"sieves", "m"}, {"radius", "m"}, {"box", "m"}, {"skin", "m"},
    {"length", "m"},
    /* counts and dimensionless numbers */
    {"number", "1"}, {"count", "1"}, {"weights", "1"}, {"fractions", "1"}, {"atol", "1"},
    {"particles", "1"}, {"rtol", "1"}, {"ratio", "1"}, {"porosity", "1"}, {"min_content", "1"},
    {"carried_ratio", "1"}, {"alpha", "1"}, {"delta", "1"}, {"exponent", "1"}, {"shape", "1"},
    {"fragments", "1"}, {"e", "1"}, {"nu", "1"}, {"mu_s", "1"}, {"mu_r", "1"},
    {"efficiency", "1"}, {"correction", "1"}, {"critical", "1"}, {"droplet_weight", "1"},
    {"scale", "1"},
    /* rates, masses and material properties */
    {"max_rate", "m^3/s"}, {"liquid_rate", "m^3/s"}, {"mass_rate", "kg/s"}, {"air_flow", "kg/s"},
    {"air_mass", "kg"}, {"solid_mass", "kg"}, {"density", "kg/m^3"}, {"densities", "kg/m^3"},
    {"velocity", "m/s"}, {"u_break", "m/s"}, {"gravity", "m/s^2"}, {"rpm", "rpm"}, {"E", "Pa"},
    {"viscosity", "Pa s"}, {"temperature", "K"}, {"bed_temperature", "K"},
    {"inlet_temperature", "K"}, {"spray_temperature", "K"}, {"initial_temperature", "K"},
    {"ambient_temperature", "K"}, {"heat_loss", "W"}, {"wall_coefficient", "W/K"},
    {"latent_heat", "J/kg"}, {"diffusivity", "m^2/s"}, {"table_limit_mb", "MiB"},
};

const char *gs_study_key_unit(const char *key) {
  /* the last name that is not a list index: `sieves.2` is a sieve */
  const char *end = key + strlen(key), *name;
  for (;;) {
    name = end;
    while (name > key && name[-1] != '.') name--;
    int index = name < end;
    for (const char *p = name; p < end; p++) index &= isdigit((unsigned char)*p) != 0;
    if (!index || name == key) break;
    end = name - 1;
  }
  const size_t n = (size_t)(end - name);
  if (n > 14 && !strncmp(end - 14, "_heat_capacity", 14)) return "J/(kg K)";
  for (size_t i = 0; i < sizeof table / sizeof *table; i++)
    if (strlen(table[i].name) == n && !strncmp(table[i].name, name, n)) return table[i].unit;
  return GS_STUDY_CASE_UNIT;
}

void gs_study_header(const char *name, const char *unit, char *buf, size_t n) {
  snprintf(buf, n, "%s [%s]", name, unit);
}
