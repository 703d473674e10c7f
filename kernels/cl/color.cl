// Colour helpers. Shader colours are linear RGB in [0, 1].

float pt_luminance(float3 c) { return dot(c, (float3)(0.2126f, 0.7152f, 0.0722f)); }

// Piecewise-linear ramp through three colours at t = 0, 0.5, 1.
float3 pt_ramp3(float t, float3 c0, float3 c1, float3 c2) {
  t = clamp(t, 0.0f, 1.0f);
  return t < 0.5f ? mix(c0, c1, t * 2.0f) : mix(c1, c2, t * 2.0f - 1.0f);
}

// Varies a colour's brightness by a factor in [1 - amount, 1 + amount] and its hue slightly,
// driven by a uniform random number r in [0, 1) (per brick, per stone, per plank).
float3 pt_vary_color(float3 c, float amount, float r, float r2) {
  const float brightness = 1.0f + amount * (2.0f * r - 1.0f);
  const float3 tint = (float3)(1.0f + 0.3f * amount * (r2 - 0.5f), 1.0f,
                               1.0f - 0.3f * amount * (r2 - 0.5f));
  return clamp(c * brightness * tint, 0.0f, 1.0f);
}

float3 pt_saturate3(float3 c) { return clamp(c, 0.0f, 1.0f); }
