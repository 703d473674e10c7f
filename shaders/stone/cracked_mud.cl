// @shader "Cracked mud: dried plates separated by dark cracks, with fine secondary cracks"
// @param float scale       = 6    [2, 24] log         "Plates across the texture"
// @param float crack_width = 0.06 [0.01, 0.3] log     "Crack width, fraction of a plate"
// @param float fine_cracks = 0.5  [0, 1]              "Strength of the secondary, finer cracks"
// @param float curl        = 0.4  [0, 1]              "Lighter, curled-up plate edges"
// @param float irregularity = 0.5 [0, 1]              "Wobble of the crack lines"
// @param color mud_color   = (0.45, 0.34, 0.22)      "Mud colour (linear RGB)"
// @param color crack_color = (0.06, 0.04, 0.03)      "Crack colour (linear RGB)"
// @param float variation   = 0.2  [0, 1]             "Plate-to-plate colour variation"
// @param float roughness   = 0.4  [0, 1]             "Surface texture"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  float2 q = p * P.scale;
  const float w = fw * P.scale;
  q = pt_warp(q, w, 0.2f * P.irregularity, 2.0f, 2, pt_subseed(seed, 1u));
  const PtVoronoi v = pt_voronoi(q, 1.0f, seed);
  const float d = 0.5f * P.crack_width - v.edge;
  const float plate = pt_coverage(d, w);
  // Secondary cracks: a finer cellular pattern, thinner, only inside plates.
  const float2 q2 = q * 2.7f;
  const PtCellular c2 = pt_cellular(q2, 1.0f, pt_subseed(seed, 2u));
  const float d2 = 0.25f * P.crack_width * 2.7f - 0.5f * (c2.f2 - c2.f1);
  const float fine = P.fine_cracks * (1.0f - pt_coverage(d2, w * 2.7f)) * 0.8f;
  float3 mc = pt_vary_color(P.mud_color, P.variation, v.id, pt_rand(v.cell.x, v.cell.y, 1, seed));
  mc *= 1.0f + P.curl * 0.35f * (1.0f - smoothstep(0.0f, 0.2f, -d));
  const float n = pt_fbm(q * 3.0f, w * 3.0f, 3, 2.0f, 0.6f, pt_subseed(seed, 3u));
  mc *= 1.0f + P.roughness * 0.4f * n;
  mc = mix(mc, P.crack_color, fine);
  return pt_saturate3(mix(P.crack_color, mc, plate));
}
