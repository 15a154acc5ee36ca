// Counts heap allocations while armed, so a Linux program or test can show that a control
// loop made none (common and firmware never allocate: a control step must not wait on, or
// fail in, the allocator). Link the CMake target hmpc::heap_monitor: it wraps the C
// allocator (--wrap=malloc,...) and routes operator new through it.
#pragma once

#include <cstdint>

namespace hmpc::platform::heap_monitor {

void arm();
void disarm();
std::uint64_t allocations();  // made while armed

}  // namespace hmpc::platform::heap_monitor
