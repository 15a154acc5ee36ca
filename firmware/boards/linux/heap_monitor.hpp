// Counts heap allocations while armed, so the board can report that its control loop made
// none (DESIGN.md §2: nothing in firmware allocates). heap_monitor.cpp wraps the C allocator
// (the program links with --wrap=malloc,...) and routes operator new through it.
#pragma once

#include <cstdint>

namespace hmpc::linux_board::heap_monitor {

void arm();
void disarm();
std::uint64_t allocations();  // made while armed

}  // namespace hmpc::linux_board::heap_monitor
