// @shader "A centred superellipse |x/a|^n + |y/b|^n = 1: diamond (n=1), ellipse (n=2), rectangle (large n)"
// @param float width    = 0.7  [0.05, 0.95]         "Width, fraction of the texture"
// @param float height   = 0.7  [0.05, 0.95]         "Height, fraction of the texture"
// @param float exponent = 3    [1, 40] log          "Shape exponent n: 1 diamond, 2 ellipse, large rectangle"
// @param float rotation = 0    [0, 90] exchange=width/height "Rotation in degrees"
// @param float softness = 0    [0, 0.5]             "Edge blur, fraction of the shape size"
// @param color fg       = (0.10, 0.30, 0.70)        "Shape colour (linear RGB)"
// @param color bg       = (0.90, 0.88, 0.82)        "Background colour (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 q = pt_rotate(p - 0.5f, -radians(P.rotation));
  const float d = pt_sd_superellipse(q, 0.5f * (float2)(P.width, P.height), P.exponent);
  return mix(P.bg, P.fg, pt_coverage(d, fw + P.softness * fmin(P.width, P.height)));
}
