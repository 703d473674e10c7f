// @shader "Crumpled paper: faceted creases at several scales, lit from one side, with fibres"
// @param float scale       = 4    [1.5, 12] log       "Large creased facets across the texture"
// @param float crumple     = 0.5  [0.1, 1]              "Strength of the facet shading"
// @param float detail      = 0.5  [0, 1]              "Weight of the smaller crease layers"
// @param color paper_color = (0.80, 0.78, 0.72) [0.05, 1] "Paper colour (linear RGB)"
// @param float fibres      = 0.3  [0, 1]              "Paper fibre texture"
// @param float light_angle = 135  [0, 360] fixed      "Direction the light comes from, in degrees"

// One layer of facets: each Voronoi cell is a flat facet with a random tilt. Facet edges are
// blended towards flat within a pixel of the crease (antialiasing), facets smaller than about
// two pixels fade out.
float facet_layer(float2 q, float w, float2 light, uint seed) {
  const PtCellular c = pt_cellular(q, 1.0f, seed);
  const float2 tilt = pt_rand2(c.cell.x, c.cell.y, seed ^ 0xabcdefU) - 0.5f;
  const float s = dot(tilt, light);
  const float e = 0.5f * (c.f2 - c.f1);  // about the distance to the crease
  const float border = clamp(e / fmax(w, 1e-6f) + 0.5f, 0.0f, 1.0f);
  // The crease itself: a thin ridge (bright) or valley (dark), drawn as a filtered line.
  const float ridge = (pt_u01(pt_hash2(c.cell.x, c.cell.y, seed ^ 0x51ed27U)) - 0.5f) * 0.6f;
  const float crease = ridge * pt_line_coverage(e, 0.015f, w);
  return (s * border + crease) * pt_detail_weight(1.0f / w);
}

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float la = radians(P.light_angle);
  const float2 light = (float2)(native_cos(la), -native_sin(la));
  const float2 q = p * P.scale;
  const float w = fw * P.scale;
  float s = facet_layer(q, w, light, pt_subseed(seed, 1u));
  s += P.detail * 0.6f * facet_layer(q * 2.3f + 1.7f, w * 2.3f, light, pt_subseed(seed, 2u));
  s += P.detail * 0.35f * facet_layer(q * 5.1f + 4.1f, w * 5.1f, light, pt_subseed(seed, 3u));
  const float f = pt_fbm(p * 90.0f, fw * 90.0f, 2, 2.0f, 0.5f, pt_subseed(seed, 4u));
  const float3 c = P.paper_color * (1.0f + 0.9f * P.crumple * s + 0.12f * P.fibres * f);
  return pt_saturate3(c);
}
