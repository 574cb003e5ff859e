#pragma once
/// \file Files compiled into multicue for report pages: the page style (always) and the viewer
/// script (three.js and web/src/viewer.js, bundled at build time when web/node_modules exists).

#include <string>
#include <string_view>

namespace multicue::report_assets {

/// True when the viewer script is compiled in.
bool HasViewer();
/// The bundled three.js version, "" without the viewer.
std::string_view ThreeVersion();
/// The minified viewer script, "" without the viewer.
const std::string& ViewerScript();
/// The page style (web/src/report.css).
std::string_view PageStyle();

}  // namespace multicue::report_assets
