// @shader "A centred rectangle on a background (rounded corners, rotation, soft edge)"
// @param float width    = 0.6  [0.05, 0.95]         "Width, fraction of the texture"
// @param float height   = 0.4  [0.05, 0.95]         "Height, fraction of the texture"
// @param float corner   = 0    [0, 1]               "Corner rounding (1: ends fully round)"
// @param float rotation = 0    [0, 90] exchange=width/height "Rotation in degrees"
// @param float softness = 0    [0, 0.5]             "Edge blur, fraction of the shape size"
// @param color fg       = (0.85, 0.20, 0.10)        "Shape colour (linear RGB)"
// @param color bg       = (0.90, 0.88, 0.82)        "Background colour (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 q = pt_rotate(p - 0.5f, -radians(P.rotation));
  const float2 h = 0.5f * (float2)(P.width, P.height);
  const float d = pt_sd_round_box(q, h, P.corner * fmin(h.x, h.y));
  return mix(P.bg, P.fg, pt_coverage(d, fw + P.softness * fmin(P.width, P.height)));
}
