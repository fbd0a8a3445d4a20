// dsreg — the files every HTML page inlines, embedded when dsreg is built
// (cmake/embed_viewer_assets.cmake generates their definitions).
#pragma once

namespace dsreg::viewer_assets {

extern const char* const three_revision;     ///< "111"
extern const char* const licence;            ///< three.js copyright line and licence (Expat), plain text
extern const char* const three_js;           ///< three.min.js (Debian libjs-three)
extern const char* const orbit_controls_js;  ///< examples/js/controls/OrbitControls.js (Debian libjs-three)
extern const char* const errors_js;          ///< src/viewer/errors.js
extern const char* const viewer_js;          ///< src/viewer/viewer.js
extern const char* const viewer_css;         ///< src/viewer/viewer.css

}  // namespace dsreg::viewer_assets
