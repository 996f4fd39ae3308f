// C ABI over Debian's libsumo (C++). Every exported function catches every C++ exception and turns
// it into a status code plus a message kept in `g_error`, so no exception ever unwinds into Rust.
// Strings and arrays handed back stay owned by this file and are valid until the next call of the
// same function; the Rust side copies them at once.
// Compiled twice: as is over libsumo (SUMO in this process), and with BK_TRACI defined
// (shim_traci.cpp) over libtraci, SUMO's C++ TraCI client with the same API, which drives a
// separate sumo-gui. The exported names then start with `bkt_` instead of `bk_`.
#ifdef BK_TRACI
#include <libsumo/libtraci.h>
#define BK(name) bkt_##name
#else
#include <libsumo/libsumo.h>
#define BK(name) bk_##name
#endif

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

// The API classes live in libsumo:: or libtraci::; the data types in libsumo:: for both.
namespace api = LIBSUMO_NAMESPACE;

namespace {

std::string g_error;

template <typename F>
int guarded(F&& body) {
    try {
        body();
        return 0;
    } catch (const libsumo::TraCIException& e) {
        g_error = e.what();
    } catch (const libsumo::FatalTraCIError& e) {
        g_error = e.what();
    } catch (const std::exception& e) {
        g_error = e.what();
    } catch (...) {
        g_error = "unknown C++ exception inside libsumo";
    }
    if (g_error.empty()) {
        g_error = "libsumo failed without a message";
    }
    return -1;
}

// Joins strings into one NUL-separated buffer (each string followed by '\0').
void join(const std::vector<std::string>& items, std::string& out) {
    out.clear();
    for (const auto& s : items) {
        out += s;
        out.push_back('\0');
    }
}

std::string g_list;
std::vector<std::string> g_edge_names;
std::string g_vehicle_strings;
std::string g_collision_strings;
std::string g_scalar_string;

}  // namespace

extern "C" {

// One vehicle's state as read in one batch; strings (id, type, edge) travel separately.
struct BkVehicleState {
    double x;
    double y;
    double speed;
    double acceleration;
    double angle;
    double lane_position;
    double lateral_offset;
    double lateral_speed;
    int32_t lane_index;
    // Index into the edge names registered with `bk_set_edge_names`, or -1 for any other edge.
    int32_t edge_code;
};

struct BkCollision {
    double collider_speed;
    double victim_speed;
    double position;
};

const char* BK(last_error)() { return g_error.c_str(); }

// `args` holds `argc` NUL-terminated strings back to back (argv[0] included; libsumo ignores it).
int BK(start)(const char* args, size_t argc) {
    return guarded([&] {
        std::vector<std::string> cmd;
        const char* p = args;
        for (size_t i = 0; i < argc; ++i) {
            cmd.emplace_back(p);
            p += std::strlen(p) + 1;
        }
        api::Simulation::start(cmd);
    });
}

int BK(close)() {
    return guarded([] { api::Simulation::close(); });
}

int BK(step)() {
    return guarded([] { api::Simulation::step(); });
}

int BK(time)(double* out) {
    return guarded([&] { *out = api::Simulation::getTime(); });
}

// SUMO's version string ("SUMO 1.15.0"). libsumo answers before any simulation starts (the
// version compiled into the library that was loaded); libtraci asks the connected sumo-gui.
int BK(version)(const char** out, size_t* len) {
    return guarded([&] {
        g_scalar_string = api::Simulation::getVersion().second;
        *out = g_scalar_string.data();
        *len = g_scalar_string.size();
    });
}

int BK(min_expected_number)(int32_t* out) {
    return guarded([&] { *out = api::Simulation::getMinExpectedNumber(); });
}

// Id lists: 0 = vehicles now in the net, 1 = departed in the last step, 2 = arrived in the last step,
// 3 = lanes of the net, 4 = edges of the net, 5 = vehicle types loaded, 6 = vehicles whose departure
// time has come but which SUMO has not inserted yet (pending).
int BK(id_list)(int32_t which, const char** buf, size_t* len) {
    return guarded([&] {
        std::vector<std::string> ids;
        switch (which) {
            case 0: ids = api::Vehicle::getIDList(); break;
            case 1: ids = api::Simulation::getDepartedIDList(); break;
            case 2: ids = api::Simulation::getArrivedIDList(); break;
            case 3: ids = api::Lane::getIDList(); break;
            case 4: ids = api::Edge::getIDList(); break;
            case 5: ids = api::VehicleType::getIDList(); break;
            case 6: ids = api::Simulation::getPendingVehicles(); break;
            default: throw std::runtime_error("unknown id list selector");
        }
        join(ids, g_list);
        *buf = g_list.data();
        *len = g_list.size();
    });
}

// Registers the edges whose vehicles `bk_read_vehicles` reports by index (NUL-separated names).
int BK(set_edge_names)(const char* names, size_t count) {
    return guarded([&] {
        g_edge_names.clear();
        const char* p = names;
        for (size_t i = 0; i < count; ++i) {
            g_edge_names.emplace_back(p);
            p += std::strlen(p) + 1;
        }
    });
}

int BK(vehicle_type)(const char* id, const char** out, size_t* len) {
    return guarded([&] {
        g_scalar_string = api::Vehicle::getTypeID(id);
        *out = g_scalar_string.data();
        *len = g_scalar_string.size();
    });
}

// The edges of a vehicle's route, NUL-separated (also of one not yet inserted).
int BK(vehicle_route)(const char* id, const char** buf, size_t* len) {
    return guarded([&] {
        join(api::Vehicle::getRoute(id), g_list);
        *buf = g_list.data();
        *len = g_list.size();
    });
}

// Reads every vehicle in the net: states into an internal array and the ids, NUL-separated, in
// the same order. Vehicle types never change, so they are asked for once (`bk_vehicle_type`).
int BK(read_vehicles)(const BkVehicleState** states, size_t* count, const char** strings,
                     size_t* strings_len) {
    static std::vector<BkVehicleState> buffer;
    return guarded([&] {
        const std::vector<std::string> ids = api::Vehicle::getIDList();
        buffer.clear();
        buffer.reserve(ids.size());
        g_vehicle_strings.clear();
        for (const auto& id : ids) {
            const libsumo::TraCIPosition pos = api::Vehicle::getPosition(id);
            BkVehicleState s{};
            s.x = pos.x;
            s.y = pos.y;
            s.speed = api::Vehicle::getSpeed(id);
            s.acceleration = api::Vehicle::getAcceleration(id);
            s.angle = api::Vehicle::getAngle(id);
            s.lane_position = api::Vehicle::getLanePosition(id);
            s.lateral_offset = api::Vehicle::getLateralLanePosition(id);
            s.lateral_speed = api::Vehicle::getLateralSpeed(id);
            s.lane_index = api::Vehicle::getLaneIndex(id);
            const std::string edge = api::Vehicle::getRoadID(id);
            s.edge_code = -1;
            for (size_t e = 0; e < g_edge_names.size(); ++e) {
                if (g_edge_names[e] == edge) {
                    s.edge_code = static_cast<int32_t>(e);
                    break;
                }
            }
            buffer.push_back(s);
            g_vehicle_strings += id;
            g_vehicle_strings.push_back('\0');
        }
        *states = buffer.data();
        *count = buffer.size();
        *strings = g_vehicle_strings.data();
        *strings_len = g_vehicle_strings.size();
    });
}

// Collisions of the last step: numbers into an internal array, and
// "collider\0victim\0colliderType\0victimType\0kind\0lane\0" per collision.
int BK(collisions)(const BkCollision** items, size_t* count, const char** strings,
                  size_t* strings_len) {
    static std::vector<BkCollision> buffer;
    return guarded([&] {
        const std::vector<libsumo::TraCICollision> cs = api::Simulation::getCollisions();
        buffer.clear();
        g_collision_strings.clear();
        for (const auto& c : cs) {
            buffer.push_back(BkCollision{c.colliderSpeed, c.victimSpeed, c.pos});
            for (const std::string* s : {&c.collider, &c.victim, &c.colliderType, &c.victimType,
                                         &c.type, &c.lane}) {
                g_collision_strings += *s;
                g_collision_strings.push_back('\0');
            }
        }
        *items = buffer.data();
        *count = buffer.size();
        *strings = g_collision_strings.data();
        *strings_len = g_collision_strings.size();
    });
}

int BK(set_speed)(const char* id, double speed) {
    return guarded([&] { api::Vehicle::setSpeed(id, speed); });
}

// Inserts a vehicle now (SUMO retries each step while its entry is blocked).
int BK(vehicle_add)(const char* id, const char* route, const char* type, int32_t lane, double speed) {
    return guarded([&] {
        char speed_text[64];
        std::snprintf(speed_text, sizeof speed_text, "%.6f", speed);
        api::Vehicle::add(id, route, type, "now", std::to_string(lane), "base", speed_text);
    });
}

// Takes a vehicle out of the simulation (as "vaporized").
int BK(vehicle_remove)(const char* id) {
    return guarded([&] { api::Vehicle::remove(id, libsumo::REMOVE_VAPORIZED); });
}

// setSpeed for `count` vehicles at once: `ids` NUL-separated, `speeds` in the same order.
int BK(set_speeds)(const char* ids, size_t count, const double* speeds) {
    return guarded([&] {
        const char* p = ids;
        for (size_t i = 0; i < count; ++i) {
            api::Vehicle::setSpeed(p, speeds[i]);
            p += std::strlen(p) + 1;
        }
    });
}

int BK(set_max_speed)(const char* id, double speed) {
    return guarded([&] { api::Vehicle::setMaxSpeed(id, speed); });
}

int BK(set_speed_mode)(const char* id, int32_t mode) {
    return guarded([&] { api::Vehicle::setSpeedMode(id, mode); });
}

int BK(set_lane_change_mode)(const char* id, int32_t mode) {
    return guarded([&] { api::Vehicle::setLaneChangeMode(id, mode); });
}

int BK(change_lane)(const char* id, int32_t lane_index, double duration) {
    return guarded([&] { api::Vehicle::changeLane(id, lane_index, duration); });
}

int BK(vehicle_size)(const char* id, double* length, double* width) {
    return guarded([&] {
        *length = api::Vehicle::getLength(id);
        *width = api::Vehicle::getWidth(id);
    });
}

int BK(vehicle_max_speed)(const char* id, double* out) {
    return guarded([&] { *out = api::Vehicle::getMaxSpeed(id); });
}

int BK(vehicle_speed_factor)(const char* id, double* out) {
    return guarded([&] { *out = api::Vehicle::getSpeedFactor(id); });
}

int BK(vehicle_limits)(const char* id, double* accel, double* decel, double* emergency,
                       double* tau, double* min_gap) {
    return guarded([&] {
        *accel = api::Vehicle::getAccel(id);
        *decel = api::Vehicle::getDecel(id);
        *emergency = api::Vehicle::getEmergencyDecel(id);
        *tau = api::Vehicle::getTau(id);
        *min_gap = api::Vehicle::getMinGap(id);
    });
}

int BK(vehicle_driving_distance)(const char* id, const char* edge, double pos, double* out) {
    return guarded([&] { *out = api::Vehicle::getDrivingDistance(id, edge, pos); });
}

int BK(lane_length)(const char* lane, double* out) {
    return guarded([&] { *out = api::Lane::getLength(lane); });
}

int BK(lane_width)(const char* lane, double* out) {
    return guarded([&] { *out = api::Lane::getWidth(lane); });
}

int BK(lane_max_speed)(const char* lane, double* out) {
    return guarded([&] { *out = api::Lane::getMaxSpeed(lane); });
}

int BK(edge_lane_count)(const char* edge, int32_t* out) {
    return guarded([&] { *out = api::Edge::getLaneNumber(edge); });
}

// Lane shape as "x0 y0 x1 y1 ..." (flat doubles).
int BK(lane_shape)(const char* lane, const double** xy, size_t* count) {
    static std::vector<double> buffer;
    return guarded([&] {
        const libsumo::TraCIPositionVector shape = api::Lane::getShape(lane);
        buffer.clear();
        for (const auto& p : shape.value) {
            buffer.push_back(p.x);
            buffer.push_back(p.y);
        }
        *xy = buffer.data();
        *count = buffer.size();
    });
}

// A vehicle's colour in the GUI (alpha opaque).
int BK(set_color)(const char* id, int32_t r, int32_t g, int32_t b) {
    return guarded([&] { api::Vehicle::setColor(id, libsumo::TraCIColor(r, g, b, 255)); });
}

}  // extern "C"
