#pragma once

// PHOTOMAT_HOT_LOOP marks the few loops that carry most of a fit's CPU time (decoding samples,
// the image matrix products). IMPLEMENTER CHOICE: on x86-64 with GCC each is compiled twice,
// for x86-64-v3 (AVX2 and FMA: eight floats per instruction, fused multiply-adds) and for the
// baseline Debian builds for (SSE2), and the loader picks one per process from the CPU it runs on
// (an ifunc), so one binary is both portable and fast. Within a process every call takes the same
// clone, so results are bit-identical between runs and between band heights; between machines
// with and without FMA they differ by float rounding (a fused multiply-add rounds once).
// Elsewhere (another compiler or architecture) the baseline alone is built.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define PHOTOMAT_HOT_LOOP __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define PHOTOMAT_HOT_LOOP
#endif
