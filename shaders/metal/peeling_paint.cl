// @shader "Peeling paint: cracked paint flaking off to reveal the surface beneath"
// @param float peel           = 0.35 [0.1, 0.9]       "Fraction of the paint that has flaked off"
// @param float scale          = 4    [1.5, 16] log       "Flake features across the texture"
// @param color paint_color    = (0.55, 0.62, 0.58)     "Paint colour (linear RGB)"
// @param color surface_color  = (0.25, 0.20, 0.15)     "Exposed surface colour (linear RGB)"
// @param float edge           = 0.5  [0, 1]            "Lifted paint edges: light rim and shadow"
// @param float cracks         = 0.4  [0, 1]            "Crack network in the remaining paint"
// @param float roughness      = 0.4  [0, 1]            "Texture of the exposed surface and dirt on the paint"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 q = p * P.scale;
  const float w = fw * P.scale;
  const float n = pt_fbm(q, w, 6, 2.0f, 0.55f, pt_subseed(seed, 1u));
  // fBm is roughly Gaussian: its CDF makes u roughly uniform, so `peel` is an area fraction.
  const float u = pt_normal_cdf(n / 0.25f);
  const float t = P.peel;
  const float gw = w * 3.0f;  // change of u per pixel, roughly
  const float paint = pt_aa_threshold(u, t, 0.0f, gw);
  // Rim: a thin bright band on the paint side, a shadow on the surface side.
  const float rim = pt_aa_threshold(u, t + 0.04f, 0.0f, gw) - paint * 0.0f;
  const float shadow = pt_aa_threshold(u, t - 0.06f, 0.02f, gw) * (1.0f - paint);
  const float f = pt_fbm(q * 5.0f, w * 5.0f, 4, 2.0f, 0.6f, pt_subseed(seed, 2u));
  float3 sc = P.surface_color * (1.0f + 0.6f * P.roughness * f);
  sc *= 1.0f - 0.6f * P.edge * shadow;
  float3 pc = P.paint_color * (1.0f + 0.15f * P.roughness * f);
  pc *= 1.0f + 0.3f * P.edge * (paint - rim);
  // Cracks in the paint: thin cellular network.
  const PtCellular c = pt_cellular(q * 3.0f, 1.0f, pt_subseed(seed, 3u));
  const float crack = 1.0f - pt_coverage(0.012f * 3.0f - 0.5f * (c.f2 - c.f1), w * 3.0f);
  pc = mix(pc, sc, P.cracks * (1.0f - crack) * 0.8f);
  return pt_saturate3(mix(sc, pc, paint));
}
