// Small fixed-size vector used by particle fields and pair physics (2D and 3D).
#pragma once
#include <cmath>

#include "sph/config.hpp"

namespace turbid::sph {

template <int D>
struct Vec {
  Real c[D];

  TURBID_HD static Vec zero() {
    Vec r;
    for (int k = 0; k < D; ++k) r.c[k] = Real(0);
    return r;
  }
  TURBID_HD Real& operator[](int k) { return c[k]; }
  TURBID_HD const Real& operator[](int k) const { return c[k]; }
  TURBID_HD Vec& operator+=(const Vec& o) {
    for (int k = 0; k < D; ++k) c[k] += o.c[k];
    return *this;
  }
  TURBID_HD Vec& operator-=(const Vec& o) {
    for (int k = 0; k < D; ++k) c[k] -= o.c[k];
    return *this;
  }
  TURBID_HD Vec& operator*=(Real s) {
    for (int k = 0; k < D; ++k) c[k] *= s;
    return *this;
  }
};

template <int D>
TURBID_HD inline Vec<D> operator+(Vec<D> a, const Vec<D>& b) {
  a += b;
  return a;
}
template <int D>
TURBID_HD inline Vec<D> operator-(Vec<D> a, const Vec<D>& b) {
  a -= b;
  return a;
}
template <int D>
TURBID_HD inline Vec<D> operator*(Vec<D> a, Real s) {
  a *= s;
  return a;
}
template <int D>
TURBID_HD inline Vec<D> operator*(Real s, Vec<D> a) {
  a *= s;
  return a;
}
template <int D>
TURBID_HD inline Real dot(const Vec<D>& a, const Vec<D>& b) {
  Real s = 0;
  for (int k = 0; k < D; ++k) s += a.c[k] * b.c[k];
  return s;
}
template <int D>
TURBID_HD inline Real norm2(const Vec<D>& a) {
  return dot(a, a);
}

}  // namespace turbid::sph
