// @shader "Gravel: packed angular or rounded pebbles, lit from one side, with dark gaps"
// @param float scale       = 28   [6, 60] log         "Pebbles across the texture"
// @param float gap         = 0.2  [0.02, 0.6] log     "Dark gaps between pebbles, fraction of a pebble"
// @param float angularity  = 0.6  [0, 1]              "0 rounded pebbles, 1 crushed angular stone"
// @param float lighting    = 0.8  [0, 1]              "Strength of the side lighting (relief)"
// @param color stone_color = (0.30, 0.30, 0.30)       "Mean pebble colour (linear RGB)"
// @param color gap_color   = (0.02, 0.02, 0.02)       "Shadow colour between pebbles (linear RGB)"
// @param float variation   = 0.6  [0, 1]              "Pebble-to-pebble brightness and tint variation"
// @param float roughness   = 0.3  [0, 1]              "Surface speckle"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  float2 q = p * P.scale;
  const float w = fw * P.scale;
  q = pt_warp(q, w, 0.15f, 1.0f, 2, pt_subseed(seed, 1u));
  const PtVoronoi v = pt_voronoi(q, 1.0f, seed);
  const float inner = v.edge - 0.5f * P.gap;  // distance inside the pebble
  const float cover = pt_coverage(-inner, w);
  // Height: flat-faceted (angular) or domed (rounded), 0 at the border, 1 in the middle.
  const float h = clamp(inner / fmax(inner + v.f1, 1e-4f) * 2.0f, 0.0f, 1.0f);
  const float height = mix(sqrt(h), h, P.angularity);
  // Slope facing the light (from the top left): pixels between the point and the light are lit.
  const float2 dir = (q - v.point) / fmax(v.f1, 1e-4f);
  const float facing = dot(dir, (float2)(-0.7071f, -0.7071f));
  const float ra = pt_rand(v.cell.x, v.cell.y, 2, seed);
  const float facet = mix(1.0f, 0.6f + 0.8f * ra, P.angularity);  // facets catch light unevenly
  float light = 1.0f + P.lighting * (1.1f * facing * (1.0f - 0.7f * height) * facet + 0.4f * (height - 0.5f));
  light = mix(1.0f, light, pt_detail_weight(0.5f / w));
  float3 sc = pt_vary_color(P.stone_color, P.variation, v.id, pt_rand(v.cell.x, v.cell.y, 3, seed));
  const float n = pt_fbm(q * 3.0f, w * 3.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 2u));
  sc *= light * (1.0f + P.roughness * 0.5f * n);
  // Pebbles darken into their own shadow at the rim.
  sc *= mix(0.4f, 1.0f, pt_aa_smoothstep(0.0f, 0.2f, inner, w));
  return pt_saturate3(mix(P.gap_color, sc, cover));
}
