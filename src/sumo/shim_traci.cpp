// The shim over libtraci (SUMO's C++ TraCI client), for a live view in sumo-gui: the same
// source as shim.cpp, its exported functions named bkt_* (see there).
#define BK_TRACI 1
#include "shim.cpp"
