// @shader "Polka dots on a grid or staggered layout, with optional jitter and size variation"
// @param int   dots           = 8    [2, 40]              "Dots along each side of the texture"
// @param float radius         = 0.3  [0.05, 0.5]          "Dot radius, fraction of the dot spacing"
// @param enum  layout         = staggered {grid, staggered} "Dot arrangement"
// @param float jitter         = 0    [0, 1]               "Random displacement of the dots"
// @param float size_variation = 0    [0, 1]               "Random variation of the dot sizes"
// @param float softness       = 0    [0, 1]               "Blur of the dot edges"
// @param color dot_color      = (0.85, 0.80, 0.70)        "Dot colour (linear RGB)"
// @param color background     = (0.10, 0.15, 0.40)        "Background colour (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float n = (float)P.dots;
  const float2 q = p * n;
  const float w = fw * n;
  const float row = pt_floor(q.y);
  float d = 1e9f;
  for (int dy = -1; dy <= 1; ++dy) {
    const float r_ = row + (float)dy;
    const float shift = (P.layout == LAYOUT_STAGGERED && (((int)r_) & 1)) ? 0.5f : 0.0f;
    const float col = pt_floor(q.x - shift);
    for (int dx = -1; dx <= 1; ++dx) {
      const float c_ = col + (float)dx;
      const float4 f = pt_cell_feature((int)c_, (int)r_, 0, seed);
      float2 centre = (float2)(c_ + shift + 0.5f, r_ + 0.5f);
      centre += 0.3f * P.jitter * (f.xy - pt_floor(f.xy) - 0.5f) * 2.0f * (0.5f - 0.5f * P.radius);
      const float r = P.radius * (1.0f - 0.6f * P.size_variation * f.z);
      d = fmin(d, length(q - centre) - r);
    }
  }
  const float cover = pt_coverage(d, w + 0.5f * P.softness * P.radius);
  return mix(P.background, P.dot_color, cover);
}
