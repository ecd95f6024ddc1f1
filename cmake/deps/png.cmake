find_package(PNG REQUIRED)
