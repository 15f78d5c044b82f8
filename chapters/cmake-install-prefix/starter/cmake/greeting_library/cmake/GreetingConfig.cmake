# find_package(Greeting) reads this file from <prefix>/lib/cmake/Greeting/.
# TODO: include the targets file that install(EXPORT GreetingTargets ...) writes
#       next to this file (hint: ${CMAKE_CURRENT_LIST_DIR}).
