// Moving the dome's lights to a new fit without a pop: each new light is
// paired with the old light nearest in direction, and over fade_s seconds its
// direction turns along the great circle, its colour and cone width blend
// linearly. New lights with no partner fade in from black at their own
// direction; old ones left over fade out. Pure logic, driven by time, so it
// can be tested with synthetic sequences.
#pragma once

#include <vector>

#include "ibl/light_dome.hpp"

namespace probelight {

class LightTransition {
 public:
  explicit LightTransition(double fade_s = 0.5) : fade_s_(fade_s) {}

  // Starts moving from what is shown at `now_s` to `target`. The first call
  // (nothing shown yet) shows the target at once: there is nothing to pop from.
  void retarget(const std::vector<ibl::DomeLight>& target, double now_s);
  // The lights to show at `now_s`.
  std::vector<ibl::DomeLight> at(double now_s) const;
  // True while a fade is under way at `now_s` (the lights change frame to frame).
  bool moving(double now_s) const;
  bool empty() const { return pairs_.empty(); }
  const std::vector<ibl::DomeLight>& target() const { return target_; }

 private:
  struct Pair {
    ibl::DomeLight from, to;
  };
  double fade_s_;
  double start_s_ = 0.0;
  std::vector<Pair> pairs_;
  std::vector<ibl::DomeLight> target_;
};

// One light part way from `from` to `to` (t in [0, 1]).
ibl::DomeLight blendLights(const ibl::DomeLight& from, const ibl::DomeLight& to, double t);

}  // namespace probelight
