#pragma once

// The Illinois variant of false position (Dowell & Jarratt 1971): the root of f in a bracket
// [lo, hi] whose ends have values of opposite signs. Each trial is the secant point of the
// bracket's ends and replaces the end of its own sign, so the bracket is kept; when the same end
// is replaced twice in a row, the other (stale) end's value is halved, which makes the convergence
// superlinear where plain false position would crawl from one side.

#include <cmath>

namespace canalsim::solver {

// When to stop, and how often to bisect so that the bracket keeps shrinking.
struct IllinoisOptions {
  int max_iterations = 100;
  double absolute_width = 0.0;  // stop once hi − lo ≤ absolute_width + relative_width |hi|
  double relative_width = 0.0;
  int bisect_every = 0;  // every n-th trial is the midpoint (0: only a secant point outside)
};

struct IllinoisResult {
  double lo, hi;  // the final bracket (lo = hi = last when f(last) = 0)
  double last;    // the last trial (lo when there was none)
};

template <class F>
IllinoisResult illinois(F&& f, double lo, double hi, double f_lo, double f_hi, const IllinoisOptions& o) {
  int side = 0;  // which end the last trial replaced: −1 lo, +1 hi
  double x = lo;
  for (int it = 0; it < o.max_iterations && hi - lo > o.absolute_width + o.relative_width * std::abs(hi); ++it) {
    x = f_lo != f_hi ? (lo * f_hi - hi * f_lo) / (f_hi - f_lo) : 0.5 * (lo + hi);
    const bool bisect = o.bisect_every > 0 && it % o.bisect_every == o.bisect_every - 1;
    if (!(x > lo && x < hi) || bisect) x = 0.5 * (lo + hi);
    const double fx = f(x);
    if (fx == 0.0) return {x, x, x};
    if ((fx < 0.0) == (f_lo < 0.0)) {
      lo = x;
      f_lo = fx;
      if (side == -1) f_hi *= 0.5;  // Illinois: halve the stale end's value
      side = -1;
    } else {
      hi = x;
      f_hi = fx;
      if (side == 1) f_lo *= 0.5;
      side = 1;
    }
  }
  return {lo, hi, x};
}

}  // namespace canalsim::solver
