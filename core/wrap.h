#pragma once

namespace photomat {

// `value` wrapped into [0, period): the index of a periodic (tiling) image or volume, for any
// integer value, negative ones included. period > 0.
inline int Wrap(int value, int period) {
  const int r = value % period;
  return r < 0 ? r + period : r;
}

}  // namespace photomat
