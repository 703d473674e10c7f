// @shader "Star field: antialiased stars of varied size, brightness and colour on a dark sky"
// @param float stars       = 400  [100, 6000] log     "Stars in the texture (brightest layer; faint ones scale with it)"
// @param float size        = 0.7  [0.4, 3] log       "Star size in 1/256ths of the texture"
// @param float brightness  = 0.9  [0.3, 1]           "Peak brightness of the brightest stars"
// @param float spread      = 2    [0.5, 4]           "Brightness spread: higher gives a few bright stars among many faint"
// @param float glow        = 0.3  [0, 1]             "Halo around bright stars"
// @param float color_variation = 0.4 [0, 1]          "Blue-white-orange variation of the stars"
// @param float faint       = 0.5  [0, 1]             "Density of a second layer of faint background stars"
// @param float elongation  = 0    [0, 1]             "Elongated, galaxy-like objects (deep-field look)"
// @param color star_color  = (1.0, 0.97, 0.92) [0.2, 1] "Mean star colour (linear RGB)"
// @param color sky_color   = (0.004, 0.005, 0.012) [0, 0.3] "Sky colour (linear RGB)"

// Adds the stars of one layer of n x n cells (one star per cell). Each star is a compact bump
// (1 - r^2/R^2)^3 widened by the pixel footprint with its energy kept (antialiased at any size);
// its support stays under half a cell, so only the 2 x 2 cells nearest p can reach it.
float3 star_layer(float2 p, float fw, uint seed, float n, float radius, float peak, float spread,
                  float glow, float cvar, float elong, float3 star_color) {
  const float2 q = p * n;
  const float2 base = pt_floor(q - 0.5f);
  const float w = fw * n;                          // pixel footprint in cell units
  const float s0 = fmin(radius * n, 0.12f);        // core radius in cell units
  const float s2 = fmin(s0 * s0 + 0.08f * w * w, 0.0278f);  // widened, support 3 s <= 0.5
  const float g2 = fmin(16.0f * s0 * s0 + 0.08f * w * w, 0.2025f);  // halo, support <= 0.45
  float3 sum = (float3)(0.0f);
  for (int dy = 0; dy <= 1; ++dy)
    for (int dx = 0; dx <= 1; ++dx) {
      const int cx = (int)base.x + dx, cy = (int)base.y + dy;
      const float4 f = pt_cell_feature(cx, cy, 0, seed);
      float2 d = q - f.xy;
      float stretch = 1.0f;
      if (elong > 0.0f) {
        // Random orientation and axis ratio from the star's own random numbers (area kept).
        const float2 dir = normalize((float2)(pt_fract(f.z * 13.7f), pt_fract(f.w * 17.3f)) - 0.5f + 1e-4f);
        stretch = 1.0f + 1.2f * elong * pt_fract(f.z * 7.31f + f.w * 3.17f);
        d = (float2)(dot(d, dir) / stretch, (d.x * dir.y - d.y * dir.x) * stretch);
      }
      const float r2 = dot(d, d);
      // Beyond both the widest core (c2 <= s2) and the halo this star adds nothing.
      if (r2 >= fmax(9.0f * s2, glow > 0.0f ? g2 : 0.0f)) continue;
      // Power-law brightness: many faint stars, a few bright ones; bright stars look larger.
      const float b = peak * pt_powr(f.z, spread);
      const float size2 = 0.3f + 0.7f * b / peak;    // bright stars have larger cores
      const float c2 = fmin(s2 * size2, 0.0278f / (stretch * stretch));  // long axis within half a cell
      const float k = fmax(1.0f - r2 / (9.0f * c2), 0.0f);
      float e = b * (s0 * s0 * size2 / c2) * k * k * k;
      const float h = fmax(1.0f - r2 / g2, 0.0f);
      e += glow * 0.25f * b * b * (16.0f * s0 * s0 / g2) * h * h;
      const float t = f.w * 2.0f - 1.0f;  // colour temperature
      const float3 tint = (float3)(1.0f + 0.35f * cvar * t, 1.0f, 1.0f - 0.5f * cvar * t);
      sum += e * star_color * tint;
    }
  return sum;
}

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float n = sqrt(P.stars);
  const float radius = P.size / 256.0f;
  float3 c = P.sky_color;
  c += star_layer(p, fw, pt_subseed(seed, 1u), n, radius, P.brightness, P.spread, P.glow,
                  P.color_variation, P.elongation, P.star_color);
  if (P.faint > 0.0f)
    c += star_layer(p, fw, pt_subseed(seed, 2u), n * (1.0f + 2.0f * P.faint), radius * 0.6f,
                    P.brightness * 0.25f, P.spread, 0.0f, P.color_variation, P.elongation, P.star_color);
  return pt_saturate3(c);
}
