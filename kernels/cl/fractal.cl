// Fractal sums of gradient noise. Every function takes the pixel footprint `fw` (texture units per
// pixel) and fades out octaves finer than about two pixels: analytic antialiasing by frequency
// clamping, so a 256^2 render and a box-reduced 1024^2 render agree.

// Weight of an octave of spatial frequency `freq` at footprint fw: 1 while a period spans more than
// four pixels, 0 below two pixels, smooth in between.
float pt_octave_weight(float freq, float fw) {
  const float pixels_per_period = 1.0f / (freq * fw + 1e-12f);
  return clamp(pixels_per_period * 0.5f - 1.0f, 0.0f, 1.0f);
}

// Rotates each octave's lattice so axis-aligned artefacts of octaves do not line up.
float2 pt_octave_rotate(float2 p) {
  return (float2)(0.8f * p.x - 0.6f * p.y, 0.6f * p.x + 0.8f * p.y);
}

// Fractional Brownian motion, range about [-1, 1]. lacunarity: frequency ratio between octaves
// (usually 2), gain: amplitude ratio (usually 0.5).
float pt_fbm(float2 p, float fw, int octaves, float lacunarity, float gain, uint seed) {
  float sum = 0.0f, amp = 1.0f, norm = 0.0f, freq = 1.0f;
  for (int i = 0; i < octaves; ++i) {
    const float w = pt_octave_weight(freq, fw);
    if (w <= 0.0f) {
      // Filtered octaves average to zero; count their amplitude so the scale stays the same.
      norm += amp * (1.0f - pt_powr(gain, (float)(octaves - i))) / (1.0f - gain + 1e-6f);
      break;
    }
    norm += amp;
    sum += w * amp * pt_gnoise(p, pt_subseed(seed, (uint)i));
    p = pt_octave_rotate(p) * lacunarity;
    freq *= lacunarity;
    amp *= gain;
  }
  // Normalise by the full amplitude sum so filtering out fine octaves keeps the same scale.
  return norm > 0.0f ? sum / norm : 0.0f;
}

// Turbulence: sum of |noise|, range [0, about 1]; the creases make marble veins and fire.
float pt_turbulence(float2 p, float fw, int octaves, float lacunarity, float gain, uint seed) {
  float sum = 0.0f, amp = 1.0f, norm = 0.0f, freq = 1.0f;
  for (int i = 0; i < octaves; ++i) {
    const float w = pt_octave_weight(freq, fw);
    norm += amp;
    // A filtered-out octave contributes the mean of |noise| (0.25, measured over 10^6 samples of
    // pt_gnoise), not zero. Its noise is not evaluated: mix(0.25, x, 0) is 0.25 exactly, so the
    // value is the same to the bit, and at the match's 128 px most fine octaves are filtered.
    const float v = w > 0.0f ? fabs(pt_gnoise(p, pt_subseed(seed, (uint)i))) : 0.25f;
    sum += amp * mix(0.25f, v, w);
    p = pt_octave_rotate(p) * lacunarity;
    freq *= lacunarity;
    amp *= gain;
  }
  return norm > 0.0f ? sum / norm : 0.0f;
}

// Ridged multifractal (Musgrave): sharp ridges whose detail grows on the ridges; range [0, 1].
float pt_ridged(float2 p, float fw, int octaves, float lacunarity, float gain, uint seed) {
  float sum = 0.0f, amp = 1.0f, norm = 0.0f, weight = 1.0f, freq = 1.0f;
  for (int i = 0; i < octaves; ++i) {
    const float w = pt_octave_weight(freq, fw);
    float signal = 1.0f - fabs(pt_gnoise(p, pt_subseed(seed, (uint)i)));
    signal = mix(0.59f, signal * signal, w);  // 0.59: measured mean of (1 - |pt_gnoise|)^2
    signal *= weight;
    weight = clamp(signal * 2.0f, 0.0f, 1.0f);
    sum += amp * signal;
    norm += amp;
    p = pt_octave_rotate(p) * lacunarity;
    freq *= lacunarity;
    amp *= gain;
  }
  return norm > 0.0f ? clamp(sum / norm, 0.0f, 1.0f) : 0.0f;
}

// Domain warping: displaces p by a vector fBm field of the given amplitude (texture units) and
// feature frequency; returns the warped position. Both components come from one pt_gnoise2 per
// octave (shared lattice hashes), about half the cost of two scalar fBms.
// noinline: inlined into a shader, it made spots and stones 1.8x slower (PoCL 3.1 / LLVM 15);
// called, the fused field is 7-15% faster than two pt_fbm (A/B, bench_render --ab).
__attribute__((noinline)) float2 pt_warp(float2 p, float fw, float amount, float frequency, int octaves,
                                         uint seed) {
  float2 q = p * frequency;
  const float wfw = fw * frequency;
  float2 sum = (float2)(0.0f);
  float amp = 1.0f, norm = 0.0f, freq = 1.0f;
  for (int i = 0; i < octaves; ++i) {
    const float w = pt_octave_weight(freq, wfw);
    if (w <= 0.0f) {
      // Filtered octaves average to zero; count their amplitude so the scale stays the same.
      norm += amp * (1.0f - pt_powr(0.5f, (float)(octaves - i))) / (0.5f + 1e-6f);
      break;
    }
    norm += amp;
    sum += w * amp * pt_gnoise2(q, pt_subseed(seed, 101u + (uint)i));
    q = pt_octave_rotate(q) * 2.0f;
    freq *= 2.0f;
    amp *= 0.5f;
  }
  return p + amount * (norm > 0.0f ? sum / norm : (float2)(0.0f));
}
