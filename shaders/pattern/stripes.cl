// @shader "Parallel stripes of two colours: width ratio, angle, soft edges and waviness"
// @param int   stripes        = 8   [1, 64]          "Stripe pairs across the texture"
// @param float duty           = 0.5 [0.05, 0.95]     "Fraction of each period in colour A"
// @param float angle          = 0   [0, 180]         "Direction in degrees (0: vertical stripes)"
// @param float softness       = 0   [0, 1]           "Edge softness (1: smooth sinusoid-like bands)"
// @param float wave           = 0   [0, 1]           "Waviness: sideways displacement of the stripes"
// @param float wave_frequency = 3   [1, 12] needs=wave "Waves along each stripe across the texture"
// @param color color_a        = (0.80, 0.10, 0.08)   "First colour (linear RGB)"
// @param color color_b        = (0.90, 0.88, 0.80)   "Second colour (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float a = radians(P.angle);
  const float2 dir = (float2)(native_cos(a), native_sin(a));
  const float n = (float)P.stripes;
  const float across = dot(p - 0.5f, dir);
  const float along = dot(p - 0.5f, (float2)(-dir.y, dir.x));
  const float amp = 0.5f * P.wave;                      // in stripe periods
  const float k = 2.0f * M_PI_F * P.wave_frequency;
  const float x = n * across + amp * native_sin(k * along);
  const float slope = amp * k * native_cos(k * along);
  const float grad = sqrt(n * n + slope * slope);
  const float s = P.softness * fmin(P.duty, 1.0f - P.duty);
  const float t = pt_soft_pulsetrain(P.duty, x, fw * grad, s);
  return mix(P.color_b, P.color_a, t);
}
