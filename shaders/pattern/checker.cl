// @shader "Checkerboard of two colours with box-filtered edges"
// @param int   squares = 8 [2, 64]            "Squares along each side of the texture"
// @param color color_a = (0.8, 0.8, 0.8)      "Colour of the even squares (linear RGB)"
// @param color color_b = (0.05, 0.05, 0.05)   "Colour of the odd squares (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  // One period of the pulse trains spans two squares.
  const float frequency = 0.5f * (float)P.squares;
  const float2 q = p * frequency;
  const float w = fw * frequency;
  const float a = pt_filtered_pulsetrain(0.5f, q.x, w);
  const float b = pt_filtered_pulsetrain(0.5f, q.y, w);
  // XOR of the two pulse trains, exact for box-filtered independent axes.
  const float odd = a + b - 2.0f * a * b;
  return mix(P.color_a, P.color_b, odd);
}
