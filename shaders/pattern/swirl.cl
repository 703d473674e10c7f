// @shader "Swirl: spiral arms of two colours twisting around the centre"
// @param int   arms     = 4    [1, 16]              "Number of spiral arms"
// @param float twist    = 8    [-30, 30]            "Turns of twist per texture unit of radius"
// @param float duty     = 0.5  [0.1, 0.9]           "Fraction of each arm period in colour A"
// @param float softness = 0.2  [0, 1]              "Edge softness"
// @param color color_a  = (0.90, 0.50, 0.05)        "First colour (linear RGB)"
// @param color color_b  = (0.10, 0.05, 0.30)        "Second colour (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 d = p - 0.5f;
  const float r = length(d);
  const float a = pt_atan2(d.y, d.x) * (1.0f / (2.0f * M_PI_F));  // turns
  const float n = (float)P.arms;
  const float v = n * a + P.twist * r;
  // |grad v|: angular part n / (2 pi r), radial part twist.
  const float ang = n / (2.0f * M_PI_F * fmax(r, 1e-4f));
  const float g = sqrt(ang * ang + P.twist * P.twist);
  const float s = P.softness * fmin(P.duty, 1.0f - P.duty);
  const float t = pt_soft_pulsetrain(P.duty, v, fw * g, s);
  return mix(P.color_b, P.color_a, t);
}
