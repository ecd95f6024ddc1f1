#pragma once
/// Meshes: read_mesh / write_mesh and PolygonMesh, from the I/O kit (core/io/io.h).
#include "core/io/io.h"
