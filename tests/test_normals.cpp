#include <gtest/gtest.h>

#include "multicue/surface/normals.hpp"

TEST(Normals, Placeholder) {}
