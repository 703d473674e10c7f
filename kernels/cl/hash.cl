// Integer hashing: the only source of randomness in shaders. Every function takes the texture's
// seed, so the same spec renders the same pixels and another seed gives another layout.

// A well-mixed 32-bit integer hash (lowbias32 by Chris Wellons).
uint pt_hash(uint x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

// pt_hash in 16 vector lanes at once (for shaders that test many cells together, e.g. grass).
uint16 pt_hash16(uint16 x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

uint pt_hash2(int x, int y, uint seed) {
  return pt_hash((uint)x * 0x8da6b343U ^ pt_hash((uint)y * 0xd8163841U ^ pt_hash(seed)));
}

uint pt_hash3(int x, int y, int z, uint seed) {
  return pt_hash(pt_hash2(x, y, seed) ^ ((uint)z * 0xcb1ab31fU));
}

// Uniform float in [0, 1) from the top 24 bits of a hash.
float pt_u01(uint h) { return (float)(h >> 8) * (1.0f / 16777216.0f); }

// Two independent uniforms in [0, 1) for lattice cell (x, y).
float2 pt_rand2(int x, int y, uint seed) {
  const uint h = pt_hash2(x, y, seed);
  return (float2)(pt_u01(h), pt_u01(pt_hash(h ^ 0x9e3779b9U)));
}

// Uniform float in [0, 1) for lattice cell (x, y) and a channel k.
float pt_rand(int x, int y, int k, uint seed) { return pt_u01(pt_hash3(x, y, k, seed)); }

// Derives a new seed for an independent layer of the same texture (octaves, warps, channels).
uint pt_subseed(uint seed, uint layer) { return pt_hash(seed ^ (layer * 0x68e31da4U + 0x1b56c4e9U)); }

// Fast math for shading code. PoCL's pow() costs about 14 ms per call per 256^2 image and atan2()
// about 6 ms, against about 1 ms for native_exp2/native_log2; use these outside exact maths.

// x^y for x >= 0 (0^y = 0 for y > 0; 0^0 = 1).
float pt_powr(float x, float y) { return native_exp2(y * native_log2(fmax(x, 1e-30f))); }

// atan2 with a polynomial (max error about 1e-4 rad), for angles of polar patterns.
float pt_atan2(float y, float x) {
  const float ax = fabs(x), ay = fabs(y);
  const float mx = fmax(ax, ay);
  const float t = fmin(ax, ay) / fmax(mx, 1e-30f);
  const float t2 = t * t;
  float r = ((-0.0464964749f * t2 + 0.15931422f) * t2 - 0.327622764f) * t2 * t + t;
  if (ay > ax) r = 1.57079637f - r;
  if (x < 0.0f) r = 3.14159274f - r;
  return y < 0.0f ? -r : r;
}

// Standard normal CDF, logistic approximation (max error about 0.01), for mapping roughly
// Gaussian noise to a roughly uniform value (coverage as an area fraction).
float pt_normal_cdf(float x) { return 1.0f / (1.0f + native_exp(-1.702f * x)); }

// floor() without PoCL 3.1's library call: a truncation and a compare (exact for every float:
// values of magnitude >= 2^23 are integers already and pass through, as do NaN and inf). Using it
// in the noises made a 6-octave fBm 19% faster (A/B, bench_render --ab, process CPU time).
__attribute__((overloadable)) float pt_floor(float x) {
  const float t = (float)(int)x;
  const float r = t > x ? t - 1.0f : t;
  return fabs(x) < 8388608.0f ? r : x;
}
__attribute__((overloadable)) float2 pt_floor(float2 x) { return (float2)(pt_floor(x.x), pt_floor(x.y)); }

// Fractional part x - floor(x) (OpenCL's fract() needs a second, pointer argument).
float pt_fract(float x) { return x - pt_floor(x); }
