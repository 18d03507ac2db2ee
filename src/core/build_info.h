#pragma once
// What built this library: the git commit of the source tree at build time, so results
// (stats.json, benchmark jobs) say which code made them.

namespace idyvins {

/// The source tree's commit (40 hex digits) at build time, with "-dirty" when it had
/// uncommitted changes; "unknown" when built outside a git checkout.
const char* buildCommit();

}  // namespace idyvins
