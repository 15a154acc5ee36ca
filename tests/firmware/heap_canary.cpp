// Proves the firmware heap guard: built with HMPC_CANARY_ALLOCATES this image calls malloc
// and must fail to link; built without, the identical image must link.
#include <cstdlib>

extern "C" [[noreturn]] void hmpc_fatal(const char*) {
  for (;;) {
  }
}

int main() {
#ifdef HMPC_CANARY_ALLOCATES
  void* volatile block = std::malloc(64);
  return block != nullptr;
#else
  return 0;
#endif
}
