// dsreg — libFuzzer entry point of one fuzz target, chosen at compile time by DSREG_FUZZ_TARGET
// (a string such as "vol"; fuzz/CMakeLists.txt builds one executable per target).
#include <cstdio>
#include <cstdlib>

#include "fuzz_targets.hpp"

namespace {

const dsreg::fuzz::Target& this_target() {
    static const dsreg::fuzz::Target* target = [] {
        const dsreg::fuzz::Target* found = dsreg::fuzz::find_target(DSREG_FUZZ_TARGET);
        if (found == nullptr) {
            std::fprintf(stderr, "unknown fuzz target %s\n", DSREG_FUZZ_TARGET);
            std::abort();
        }
        return found;
    }();
    return *target;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    this_target().run(data, size);
    return 0;
}
