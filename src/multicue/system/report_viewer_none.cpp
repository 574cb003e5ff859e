// Used when the build has no viewer bundle (web/node_modules missing or
// MULTICUE_REPORT_VIEWER=OFF): report pages then show their tables and a note instead of the 3D
// view.

#include <string>
#include <string_view>

#include "multicue/system/report_assets.hpp"

namespace multicue::report_assets {

bool HasViewer() { return false; }

std::string_view ThreeVersion() { return {}; }

const std::string& ViewerScript() {
    static const std::string empty;
    return empty;
}

}  // namespace multicue::report_assets
