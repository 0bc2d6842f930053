// Packet: what crosses from one environment to a neighbour when a patch has
// shot: the shooter's geometry, its power, the shot's key and the visibility
// mask so far. A fixed-size record once the mask's shape is known: a
// trivially copyable header followed by the mask's bytes (ceil(4R^2 / 8) for
// a hemisphere, ceil(N / 8) for Method R's N rays), padded to 8. The
// radiosity code packs and unpacks it; transports only move the bytes.
#pragma once
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "vismask/solve/mask.h"
#include "vismask/solve/patch.h"

namespace vismask {

// PacketHeader::flags: Method B's shot decides only the pixels its rays
// read downstream (Environment::ReadsOnly), set by its source.
constexpr uint16_t kReadsOnly = 1;

struct PacketHeader {
  uint64_t shotKey;    // regenerates the shot's random streams
  double power[3];     // the shooter's unshot power when it shot (W)
  float corner[4][3];  // the shooter's corners (corner[3] == corner[2] for triangles)
  float normal[3];
  float area;
  uint16_t numCorners;
  uint16_t flags;      // kReadsOnly
  uint32_t shooterId;  // global patch id
  uint32_t shotIndex;  // how many times the shooter had shot before
  uint32_t sourceEnv;  // where it shot first
  uint32_t fromEnv;    // the sender of this packet
  uint32_t toEnv;      // the receiver
  float flightShare;   // the receiver's share of `power` in flight (Environment::FlightShare)
  uint32_t rays;       // the shot's ray count (every environment traces as many)
  // Per-pixel direct light: the share of `power` that is its shooter's own
  // emission, per channel (DirectBook::shotDirect), which every
  // environment's pixels gather when they gather every environment's
  // emitters (foreign_light.h).
  float direct[3];
  uint16_t openCells;  // Patch::openCells: where the shot's rays leave from
  uint16_t reserved;   // 0
};
static_assert(std::is_trivially_copyable<PacketHeader>::value, "packets are plain bytes");
static_assert(sizeof(PacketHeader) == 144, "the packet header's layout is part of the wire format");
static_assert(sizeof(PacketHeader) % 8 == 0, "mask bytes start 8-aligned");

// The size in bytes of every packet of a run with mask shape `shape`.
inline uint32_t PacketBytes(const MaskShape& shape) {
  return static_cast<uint32_t>(sizeof(PacketHeader)) + ((shape.bytes() + 7) & ~7u);
}

// The header of a shot of `p` (power, key and ids; the routing fields
// fromEnv, toEnv and flightShare are left 0).
PacketHeader ShotHeader(const Patch& p, const double power[3], uint64_t shotKey, uint32_t shotIndex,
                        uint32_t sourceEnv, uint32_t rays);
// The shooter as a foreign environment sees it: corners, normal, area, corner
// count and global id, the very floats of the source's patch, so that
// MakePatchSampler and the shot's stream regenerate its rays bit for bit.
Patch PatchFromHeader(const PacketHeader& h);

inline void WriteHeader(uint8_t* packet, const PacketHeader& h) {
  std::memcpy(packet, &h, sizeof h);
}
inline PacketHeader ReadHeader(const uint8_t* packet) {
  PacketHeader h;
  std::memcpy(&h, packet, sizeof h);
  return h;
}
inline uint8_t* MaskBytes(uint8_t* packet) {
  return packet + sizeof(PacketHeader);
}
inline const uint8_t* MaskBytes(const uint8_t* packet) {
  return packet + sizeof(PacketHeader);
}

}  // namespace vismask
