// @shader "Concrete pavers: running, stack or basket-weave layout with sand joints and bevels"
// @param float scale        = 6    [2, 24] log          "Paver widths across the texture"
// @param enum  layout       = basket {running, stack, basket} "Laying pattern"
// @param float gap          = 0.05 [0.01, 0.3] log      "Joint width, fraction of a paver width"
// @param color paver_color  = (0.42, 0.40, 0.37)        "Mean paver colour (linear RGB)"
// @param color joint_color  = (0.22, 0.20, 0.17)        "Joint colour (linear RGB)"
// @param float variation    = 0.2  [0, 1]               "Paver-to-paver colour variation"
// @param float bevel        = 0.4  [0, 1]               "Darkened chamfer at the paver edges"
// @param float roughness    = 0.4  [0, 1]               "Concrete speckle and stains"
// @param float grain        = 0    [0, 1]               "Stains and grain of the paver faces at every scale down to the pixel"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 q = p * P.scale;
  const float w = fw * P.scale;
  // Pavers are 2 x 1 (units: the paver width).
  float2 lp, half_size;
  int2 id;
  if (P.layout == LAYOUT_BASKET) {
    // 2 x 2 blocks of two pavers, alternating horizontal and vertical like a checkerboard.
    const float2 b = pt_floor(q * 0.5f);
    const float2 f = q - 2.0f * b;
    const int vert = (((int)b.x + (int)b.y) & 1);
    const float along = vert ? f.x : f.y;
    const float k = pt_floor(along);
    lp = vert ? (float2)(f.x - k - 0.5f, f.y - 1.0f) : (float2)(f.x - 1.0f, f.y - k - 0.5f);
    half_size = vert ? (float2)(0.5f, 1.0f) : (float2)(1.0f, 0.5f);
    id = (int2)((int)b.x * 2 + (int)k, (int)b.y);
  } else {
    const float4 c = pt_brick_cell(q, 2.0f, P.layout == LAYOUT_RUNNING ? 0.5f : 0.0f);
    lp = c.zw - (float2)(1.0f, 0.5f);
    half_size = (float2)(1.0f, 0.5f);
    id = (int2)((int)c.x, (int)c.y);
  }
  const float d = pt_sd_round_box(lp, half_size - 0.5f * P.gap, 0.03f);
  const float cover = pt_coverage(d, w);
  float3 pc = pt_vary_color(P.paver_color, P.variation, pt_rand(id.x, id.y, 0, seed), pt_rand(id.x, id.y, 1, seed));
  const float n = pt_fbm(q * 2.0f, w * 2.0f, 5, 2.0f, 0.6f, pt_subseed(seed, 1u));
  const float fine = pt_octave_weight(24.0f, w) * pt_vnoise(q * 24.0f, pt_subseed(seed, 2u));
  pc *= 1.0f + P.roughness * (0.35f * n + 0.25f * fine);
  // Grain at every scale down to the pixel, as photographed stone and concrete show. Without it
  // only many small pavers put a photo's fine detail into a render: matches of tile and flagstone
  // photos came back 3-6x too small (session 18). Default 0: earlier specs render as they did.
  if (P.grain > 0.0f)  // the default 0 renders as before the parameter existed, at its cost
    pc *= 1.0f + P.grain * 1.2f * pt_fbm(q * 3.0f, w * 3.0f, 8, 2.0f, 0.75f, pt_subseed(seed, 5u));
  pc *= mix(1.0f, mix(1.0f - 0.5f * P.bevel, 1.0f, smoothstep(0.0f, 0.08f, -d)), pt_detail_weight(0.08f / w));
  const float3 jc = P.joint_color * (1.0f + 0.3f * n + 0.3f * fine);
  return pt_saturate3(mix(jc, pc, cover));
}
