// CABLECAL_FLATTEN: GCC's `flatten` attribute, which inlines every call in a function's body
// (recursively). For hot functions of Jet arithmetic: in a translation unit with many template
// instances GCC's inliner runs out of its unit-growth budget and calls Eigen's small fixed-size
// kernels (a Jet's derivative vector's sum, difference, scaling) out of line, which can make the
// function several times slower (bench/README.md names each use and what it measured). Inlining
// does not change a result: no floating-point contraction on the x86-64 baseline. Left out under
// AddressSanitizer, where flattened units take minutes to compile and speed is not the point.
#pragma once

#if defined(CABLECAL_ADDRESS_SANITIZER) || !defined(__GNUC__)
#define CABLECAL_FLATTEN
#else
#define CABLECAL_FLATTEN __attribute__((flatten))
#endif
