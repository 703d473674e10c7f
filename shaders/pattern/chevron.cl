// @shader "Chevron (zigzag) stripes of two colours"
// @param int   stripes  = 8    [2, 40]              "Stripe pairs across the texture (vertically)"
// @param int   zigzags  = 4    [1, 20]              "Zigzag periods across the texture (horizontally)"
// @param float amplitude = 0.5 [0.1, 2]             "Zigzag height, in stripe periods"
// @param float duty     = 0.5  [0.1, 0.9]           "Fraction of each period in colour A"
// @param float softness = 0    [0, 1]               "Edge softness"
// @param color color_a  = (0.10, 0.12, 0.15)        "First colour (linear RGB)"
// @param color color_b  = (0.85, 0.83, 0.78)        "Second colour (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float z = p.x * (float)P.zigzags;
  const float tri = fabs(2.0f * (z - pt_floor(z)) - 1.0f);  // triangle wave in [0, 1]
  const float v = p.y * (float)P.stripes + P.amplitude * tri;
  // |grad v| = sqrt(stripes^2 + (2 amplitude zigzags)^2) away from the corners.
  const float sx = 2.0f * P.amplitude * (float)P.zigzags;
  const float g = sqrt((float)(P.stripes * P.stripes) + sx * sx);
  const float s = P.softness * fmin(P.duty, 1.0f - P.duty);
  return mix(P.color_b, P.color_a, pt_soft_pulsetrain(P.duty, v, fw * g, s));
}
