#pragma once
/// \file All feature estimators of the features module (thesis sections 2.5 and 4.2.3.1).

#include "multicue/features/feature_common.hpp"
#include "multicue/features/grsd.hpp"
#include "multicue/features/part_stats.hpp"
#include "multicue/features/pfh.hpp"
#include "multicue/features/registry.hpp"
#include "multicue/features/rsd.hpp"
#include "multicue/features/surface_types.hpp"
#include "multicue/features/vfh.hpp"
