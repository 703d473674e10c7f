// @shader "Corrugated cardboard: soft parallel flutes under brown kraft paper with fibres and stains"
// @param float flutes      = 24   [4, 80] log         "Flutes across the texture"
// @param float depth       = 0.4  [0.1, 1]              "Shading depth of the flutes (0: flat board)"
// @param color color       = (0.45, 0.30, 0.16) [0.05, 1] "Kraft paper colour (linear RGB)"
// @param float fibres      = 0.4  [0.1, 1]              "Paper fibre texture"
// @param float stains      = 0.2  [0, 1]              "Darker blotches and water stains"
// @param bool  vertical    = true                     "Flutes run vertically"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 a = P.vertical ? p : p.yx;
  // A smooth flute profile: a fully softened pulse train (a triangle wave), squared for roundness.
  const float x = a.x * P.flutes;
  const float tri = pt_soft_pulsetrain(0.5f, x, fw * P.flutes, 0.5f);
  const float prof = mix(tri, tri * tri * (3.0f - 2.0f * tri), 0.5f);
  float3 c = P.color * (1.0f - 0.35f * P.depth + 0.5f * P.depth * prof);
  const float f = pt_fbm((float2)(a.x * 60.0f, a.y * 25.0f), fw * 60.0f, 4, 2.0f, 0.6f, pt_subseed(seed, 1u));
  const float st = pt_fbm(p * 3.0f, fw * 3.0f, 5, 2.0f, 0.5f, pt_subseed(seed, 2u));
  c *= 1.0f + 0.25f * P.fibres * f;
  c *= 1.0f - 0.35f * P.stains * smoothstep(0.05f, 0.4f, st);
  return pt_saturate3(c);
}
