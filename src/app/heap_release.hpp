// Gives the allocator's free pages back to the system after the rare heavy
// events of a long run: a recalibration (its bracket's frames, the merge,
// the fit), the stored lighting restored, a camera's restart (a replay
// lists its folder again). Their temporaries are freed at once, but glibc
// returns heap pages to the system only from the top of the heap (and
// raises its mmap threshold to the largest block freed, so later blocks of
// that size come from the heap as well): the process kept the peak of each
// new kind of event resident, 2-3 MiB in steps over a 100,000-frame soak,
// while the memory it held (mallinfo2) stayed flat. malloc_trim returns the
// free pages from anywhere in every arena, in about a millisecond; the
// frame loop's own per-frame temporaries are left alone (trimmed pages
// would only fault in again on the next frame).
#pragma once

#include <cstddef>

namespace probelight {

// Returns free heap pages to the system (glibc's malloc_trim(0)); false
// where the allocator has nothing to give back or is not glibc's (a
// sanitizer's, or another libc).
bool releaseFreeHeapToSystem();

// When to release: after a frame in which a heavy event ended. `events` is
// the running count of them (calibrations, restores, reconnects), which
// only rises.
class HeapReleasePolicy {
 public:
  // True once per rise of `events` since the last call: release now.
  bool releaseAfter(long long events) {
    const bool rose = events > seen_;
    if (rose) seen_ = events;
    return rose;
  }

 private:
  long long seen_ = 0;
};

}  // namespace probelight
