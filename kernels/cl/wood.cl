// Wood: growth rings for the wood family (planks, parquet, end grain). `a` is the position in the
// tree's cross-section (texture units, pith at the origin; callers compress the coordinate along
// the grain to elongate the rings) and fw the footprint in those units.
float3 pt_wood(float2 a, float fw, float rings, float distortion, float late_wood, float softness,
               float grain, float3 light, float3 dark, uint seed) {
  const float n = pt_fbm(a * 3.0f, fw * 3.0f, 5, 2.0f, 0.5f, pt_subseed(seed, 1u));
  const float radius = length(a);
  float r = radius * rings + distortion * 1.5f * n;
  // Uneven ring widths: good and bad growth years.
  r += 0.5f * distortion * pt_gnoise((float2)(r * 0.37f, 0.5f), pt_subseed(seed, 4u));
  // |grad r| <= rings plus the noise's slope.
  const float wr = fw * (rings + distortion * 9.0f) * (1.0f + 0.4f * distortion);
  const float s = softness * fmin(late_wood, 1.0f - late_wood);
  const float late = pt_soft_pulsetrain(late_wood, r, wr, s);
  float3 c = mix(light, dark, late);
  // Grain: pores and streaks, long along the grain, fine across it.
  const float2 g = (float2)(a.x * 4.0f, radius * 60.0f + 15.0f * n);
  const float gn = pt_fbm(g, fw * 60.0f, 2, 2.0f, 0.5f, pt_subseed(seed, 2u));
  const float slow = pt_octave_weight(12.0f, fw) * pt_gnoise(a * (float2)(1.0f, 12.0f), pt_subseed(seed, 3u));
  c *= 1.0f + grain * (0.35f * gn + 0.2f * slow) - 0.1f * grain * late;
  return c;
}
