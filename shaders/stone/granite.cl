// @shader "Granite: interlocking mineral grains in dark, mid and light tones with mottling"
// @param float scale       = 30   [10, 120] log       "Grains across the texture"
// @param color dark_color  = (0.03, 0.03, 0.03)      "Dark mineral (mica, hornblende)"
// @param color mid_color   = (0.45, 0.30, 0.26)      "Main mineral (feldspar)"
// @param color light_color = (0.75, 0.74, 0.72)      "Light mineral (quartz)"
// @param float dark_fraction  = 0.25 [0, 0.7]        "Fraction of dark grains"
// @param float light_fraction = 0.2  [0, 0.7]        "Fraction of light grains"
// @param float mottle      = 0.3  [0, 1]             "Large-scale cloudy variation"
// @param float speckle     = 0.3  [0, 1]             "Variation inside and between grains"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 q = p * P.scale;
  const float w = fw * P.scale;
  const PtCellular c = pt_cellular(q, 0.9f, seed);
  const float u = c.id;
  const float df = P.dark_fraction, lf = fmin(P.light_fraction, 1.0f - df);
  float3 grain = u < df ? P.dark_color : (u > 1.0f - lf ? P.light_color : P.mid_color);
  const float r = pt_u01(pt_hash2(c.cell.x, c.cell.y, seed ^ 0x1234567U));
  grain *= 1.0f + (0.15f + P.speckle * 0.6f) * (r - 0.5f);
  // Mean colour of the grain mix: what a pixel covering many grains sees.
  const float3 mean = df * P.dark_color + lf * P.light_color + (1.0f - df - lf) * P.mid_color;
  // Blend towards the mean near grain borders (half of F2 - F1 is about the border distance).
  const float border = clamp(0.5f * (c.f2 - c.f1) / fmax(w, 1e-6f), 0.0f, 1.0f);
  // A pixel covering N ~ w^2 grains averages them: their contrast drops like 1 / sqrt(N).
  const float resolve = rsqrt(1.0f + 1.5f * w * w);
  float3 col = mix(mean, grain, mix(1.0f, fmin(0.5f + border, 1.0f), fmin(w, 1.0f)) * resolve);
  const float m = pt_fbm(p * 4.0f, fw * 4.0f, 5, 2.0f, 0.5f, pt_subseed(seed, 1u));
  col *= 1.0f + P.mottle * 0.5f * m;
  return pt_saturate3(col);
}
