/* The sprayed rotating drum of the spray and granulation tests
 * (tests/test_dem_spray.c, test_dem_granulation.c): soft particles of the
 * paper's shear modulus, a drum turning at 30 rpm between two planes and 250
 * particles of 1 mm radius; a case adds its dem:, spray:, granulation: and
 * output: sections around it. */
#ifndef GRANSIM_WET_TESTLIB_H
#define GRANSIM_WET_TESTLIB_H

#define WET_DRUM_BED \
  "materials:\n" \
  "  - {name: powder, E: 2.5e6, nu: 0.25, e: 0.1, mu_s: 0.5, density: 1030}\n" \
  "classes:\n" \
  "  - {name: primary, radius: 1.0e-3, material: powder}\n" \
  "walls:\n" \
  "  - name: drum\n" \
  "    cylinder: {point: [0, 0, 0], axis: [0, 0, 1], radius: 0.03}\n" \
  "    material: powder\n" \
  "    rotation: {origin: [0, 0, 0], axis: [0, 0, 1], rpm: 30}\n" \
  "  - {name: front, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: powder}\n" \
  "  - {name: back, plane: {point: [0, 0, 0.02], normal: [0, 0, -1]}, material: powder}\n" \
  "fill:\n" \
  "  - region: {box: {lo: [-0.02, -0.028, 0.002], hi: [0.02, -0.005, 0.018]}}\n" \
  "    count: 250\n"

#endif
