// libFuzzer's entry point for one target, named by MESHMEND_FUZZ_TARGET
// (fuzz/CMakeLists.txt): a Finding, or any exception that is not one of the
// core's typed errors (the bodies catch those: a refusal is a clean
// outcome), aborts with its message, which libFuzzer records as a crash.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>

#include "fuzz/fuzz_input.h"

namespace {

meshmend::fuzz::Body bodyNamed(const char* name) {
  for (const auto& t : meshmend::fuzz::targets())
    if (std::strcmp(t.name, name) == 0) return t.body;
  std::fprintf(stderr, "no fuzz target named %s\n", name);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const meshmend::fuzz::Body body = bodyNamed(MESHMEND_FUZZ_TARGET);
  try {
    body(data, size);
  } catch (const meshmend::fuzz::Finding& e) {
    std::fprintf(stderr, "FINDING (%s): %s\n", MESHMEND_FUZZ_TARGET, e.what());
    std::abort();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "FINDING (%s): unexpected exception: %s\n", MESHMEND_FUZZ_TARGET,
                 e.what());
    std::abort();
  }
  return 0;
}
