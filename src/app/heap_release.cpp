#include "app/heap_release.hpp"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace probelight {

bool releaseFreeHeapToSystem() {
#if defined(__GLIBC__)
  return malloc_trim(0) == 1;
#else
  return false;
#endif
}

}  // namespace probelight
