#pragma once
/// Point clouds: read_points / write_points_xyz and PointCloud, from the I/O kit (core/io/io.h).
#include "core/io/io.h"
