find_package(OpenMesh REQUIRED)
