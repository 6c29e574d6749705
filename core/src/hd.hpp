// What host and device code share below the algorithms: the annotation that
// compiles a function for both, the few atomics the per-element code needs,
// and the transcendental functions, written here because the host's libm and
// CUDA's round them differently and the surface must be the same bytes on
// either. Everything else the per-element code computes is IEEE arithmetic
// (+, -, *, /, sqrt, each rounded once: the host is built with
// -ffp-contract=off and the device with --fmad=false), which both sides
// round alike.
//
// Header-only and C++17: the CUDA units include it too.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>

#ifdef __CUDACC__
#define TETISO_HD __host__ __device__
#define TETISO_INLINE __forceinline__
#else
#define TETISO_HD
#define TETISO_INLINE inline __attribute__((always_inline))
#endif

namespace tetiso::hd {

// Relaxed atomics: the value is all that matters (a minimum, a mark, a
// count), never the order of other memory operations around them. The host
// side uses GCC's builtins, which C++17 code may call (std::atomic_ref is
// C++20).
#ifndef __CUDA_ARCH__
// *at = value where better(value, *at), by compare-and-swap.
template <class T, class Better>
inline void replace_if(T* at, T value, const Better& better) {
    T seen = __atomic_load_n(at, __ATOMIC_RELAXED);
    while (better(value, seen) &&
           !__atomic_compare_exchange_n(at, &seen, value, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
    }
}
#endif

// For int32 and uint64 (the types CUDA's atomics take).
template <class T>
TETISO_HD inline void atomic_min(T* at, T value) {
    static_assert(std::is_same_v<T, std::int32_t> || std::is_same_v<T, std::uint64_t>);
#ifdef __CUDA_ARCH__
    if constexpr (std::is_same_v<T, std::uint64_t>)
        atomicMin(reinterpret_cast<unsigned long long*>(at), static_cast<unsigned long long>(value));
    else
        atomicMin(at, value);
#else
    replace_if(at, value, [](T a, T b) { return a < b; });
#endif
}

TETISO_HD inline void atomic_max(std::uint64_t* at, std::uint64_t value) {
#ifdef __CUDA_ARCH__
    atomicMax(reinterpret_cast<unsigned long long*>(at), static_cast<unsigned long long>(value));
#else
    replace_if(at, value, [](std::uint64_t a, std::uint64_t b) { return a > b; });
#endif
}

// A double's bits, and back (memcpy: the one conversion both compilers
// accept in C++17 on host and device).
TETISO_HD inline std::uint64_t bits(double x) {
    std::uint64_t b;
    std::memcpy(&b, &x, sizeof b);
    return b;
}
TETISO_HD inline double from_bits(std::uint64_t b) {
    double x;
    std::memcpy(&x, &b, sizeof x);
    return x;
}

template <class T>
TETISO_HD inline void atomic_store(T* at, T value) {
#ifdef __CUDA_ARCH__
    // Every thread that stores here stores the same value: a plain store of
    // an aligned word cannot tear.
    *reinterpret_cast<volatile T*>(at) = value;
#else
    __atomic_store_n(at, value, __ATOMIC_RELAXED);
#endif
}

TETISO_HD inline std::int32_t atomic_add(std::int32_t* at, std::int32_t value) {
#ifdef __CUDA_ARCH__
    return atomicAdd(at, value);
#else
    return __atomic_fetch_add(at, value, __ATOMIC_RELAXED);
#endif
}

TETISO_HD inline std::int64_t atomic_add(std::int64_t* at, std::int64_t value) {
#ifdef __CUDA_ARCH__
    return static_cast<std::int64_t>(
        atomicAdd(reinterpret_cast<unsigned long long*>(at), static_cast<unsigned long long>(value)));
#else
    return __atomic_fetch_add(at, value, __ATOMIC_RELAXED);
#endif
}

constexpr double kPi = 3.14159265358979323846;
constexpr double kHalfPi = 1.57079632679489661923;

// atan(x), within a few units in the last place. Two halvings of the angle
// (atan x = 2 atan(x / (1 + sqrt(1 + x²)))) bring |x| <= 1 below tan(π/16),
// where 12 terms of the series leave a remainder under 1e-18.
TETISO_HD inline double atan(double x) {
    const bool negative = x < 0;
    if (negative) x = -x;
    const bool inverted = x > 1.0;
    if (inverted) x = 1.0 / x;
    x = x / (1.0 + sqrt(1.0 + x * x));
    x = x / (1.0 + sqrt(1.0 + x * x));
    const double x2 = x * x;
    double sum = 0.0;
    for (int k = 23; k >= 3; k -= 2) sum = x2 * ((k % 4 == 1 ? 1.0 : -1.0) / k + sum);
    double r = 4.0 * (x + x * sum);
    if (inverted) r = kHalfPi - r;
    return negative ? -r : r;
}

// x - n·π/2 for the nearest integer n, and n mod 4. π/2 in two parts, the
// first with 33 significant bits, so n·part exactly fits a double for
// |n| < 2^20 (|x| up to about 1.6e6; the built-in fields need 50): the
// subtraction is exact and only the second part's product rounds.
TETISO_HD inline double reduce_quadrant(double x, int& quadrant) {
    constexpr double kTwoOverPi = 0.63661977236758134308;
    constexpr double kHalfPiHigh = 1.57079632673412561417e+00;
    constexpr double kHalfPiLow = 6.07710050650619224932e-11;
    const double n = floor(x * kTwoOverPi + 0.5);
    quadrant = static_cast<int>(static_cast<std::int64_t>(n) & 3);
    return (x - n * kHalfPiHigh) - n * kHalfPiLow;
}

// sin and cos of |r| <= π/4: Taylor series to r^17 and r^18, whose remainder
// is below 1e-19 there. The factorials are exact in a double.
TETISO_HD inline double sin_kernel(double r) {
    const double r2 = r * r;
    double sum = 1.0 / 355687428096000.0;   // 1/17!
    sum = 1.0 / 1307674368000.0 - r2 * sum; // 1/15!
    sum = 1.0 / 6227020800.0 - r2 * sum;
    sum = 1.0 / 39916800.0 - r2 * sum;
    sum = 1.0 / 362880.0 - r2 * sum;
    sum = 1.0 / 5040.0 - r2 * sum;
    sum = 1.0 / 120.0 - r2 * sum;
    sum = 1.0 / 6.0 - r2 * sum;
    return r - r * (r2 * sum);
}

TETISO_HD inline double cos_kernel(double r) {
    const double r2 = r * r;
    double sum = 1.0 / 6402373705728000.0;   // 1/18!
    sum = 1.0 / 20922789888000.0 - r2 * sum; // 1/16!
    sum = 1.0 / 87178291200.0 - r2 * sum;
    sum = 1.0 / 479001600.0 - r2 * sum;
    sum = 1.0 / 3628800.0 - r2 * sum;
    sum = 1.0 / 40320.0 - r2 * sum;
    sum = 1.0 / 720.0 - r2 * sum;
    sum = 1.0 / 24.0 - r2 * sum;
    sum = 0.5 - r2 * sum;
    return 1.0 - r2 * sum;
}

TETISO_HD inline double sin(double x) {
    int q;
    const double r = reduce_quadrant(x, q);
    switch (q) {
    case 0: return sin_kernel(r);
    case 1: return cos_kernel(r);
    case 2: return -sin_kernel(r);
    default: return -cos_kernel(r);
    }
}

TETISO_HD inline double cos(double x) {
    int q;
    const double r = reduce_quadrant(x, q);
    switch (q) {
    case 0: return cos_kernel(r);
    case 1: return -sin_kernel(r);
    case 2: return -cos_kernel(r);
    default: return sin_kernel(r);
    }
}

} // namespace tetiso::hd
