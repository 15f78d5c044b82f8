# Read by find_package(Greeting): brings in the imported target Greeting::greeting.
include("${CMAKE_CURRENT_LIST_DIR}/GreetingTargets.cmake")
