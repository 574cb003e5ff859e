#pragma once
/// \file All filters: NaN removal, crop box, voxel grid, statistical and radius outlier removal.

#include "multicue/filters/crop_box.hpp"
#include "multicue/filters/outlier_removal.hpp"
#include "multicue/filters/remove_non_finite.hpp"
#include "multicue/filters/voxel_grid.hpp"
