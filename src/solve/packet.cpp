#include "vismask/solve/packet.h"

namespace vismask {

PacketHeader ShotHeader(const Patch& p, const double power[3], uint64_t shotKey, uint32_t shotIndex,
                        uint32_t sourceEnv, uint32_t rays) {
  PacketHeader h{};
  h.shotKey = shotKey;
  for (int c = 0; c < 3; ++c) h.power[c] = power[c];
  for (int k = 0; k < 4; ++k)
    for (int a = 0; a < 3; ++a) h.corner[k][a] = p.corner[k][a];
  for (int a = 0; a < 3; ++a) h.normal[a] = p.normal[a];
  h.area = p.area;
  h.numCorners = static_cast<uint16_t>(p.numCorners);
  h.flags = 0;
  h.shooterId = p.globalId;
  h.shotIndex = shotIndex;
  h.sourceEnv = sourceEnv;
  h.rays = rays;
  h.openCells = p.openCells;
  return h;
}

Patch PatchFromHeader(const PacketHeader& h) {
  Patch p{};
  for (int k = 0; k < 4; ++k)
    p.corner[k] = glm::vec3(h.corner[k][0], h.corner[k][1], h.corner[k][2]);
  p.normal = glm::vec3(h.normal[0], h.normal[1], h.normal[2]);
  p.area = h.area;
  p.numCorners = h.numCorners;
  p.globalId = h.shooterId;
  p.openCells = h.openCells;
  return p;
}

}  // namespace vismask
