// Where this binary was built from, for the provenance a report records
// (generated at every build by cpp/util/build_info.cmake).
#pragma once

namespace penumbra {

// The git commit of the source tree, or "not from a git checkout".
const char* build_commit();
// 1 when cpp/, harness/ or CMakeLists.txt differed from that commit at build
// time, 0 when not, -1 when unknown (no git checkout).
int build_dirty();

}  // namespace penumbra
