#pragma once
// The web viewer's page template (with {{TITLE}}, {{DATA}} and {{SCRIPT}} slots) and its
// bundled script (three.js and viewer/src/main.js), compiled in from a source that
// cmake/embed_viewer.cmake generates. The script is empty in a build without the viewer.

#include <string_view>

namespace tetcut::view {

extern const std::string_view kViewerPage;
extern const std::string_view kViewerScript;
/// The live page of `tetcut serve` ({{CONFIG}} and {{SCRIPT}} slots) and its script (live.js).
extern const std::string_view kLivePage;
extern const std::string_view kLiveScript;

}  // namespace tetcut::view
