// Environment, its power in flight (docs/DESIGN.md, "Power in flight"): the
// power booked as shot but not yet delivered, and the share of a packet's
// hemisphere whose centre rays cross from its sender into a receiver's box
// (FlightShare), which the sender works out for its receiver.
#include <cmath>

#include "vismask/solve/centre_raster.h"
#include "vismask/solve/environment.h"
#include "vismask/solve/sampling.h"

namespace vismask {

// The power booked as shot but not yet delivered (docs/DESIGN.md, "Power
// in flight"), so that the sum over environments counts each watt once.
void Environment::FlightPower(double power[3]) const {
  const bool methodR = options_.maskMethod == MaskMethod::kR;
  for (int c = 0; c < 3; ++c) power[c] = methodR ? ledger_.inFlight[c] : 0.0;
  if (methodR) return;
  exchange_.queue().AddFlightPower(power);
  // The packets not yet delivered: their receivers' shares (Forward).
  const Outbox& outbox = exchange_.outbox();
  for (uint32_t k = 0; k < outbox.count(); ++k) {
    PacketHeader h = ReadHeader(outbox.Packet(k));
    for (int c = 0; c < 3; ++c) power[c] += h.power[c] * h.flightShare;
  }
}

// The share FlightShare gives a packet addressed here with this box (what
// its sender put in it).
double Environment::FlightShareAt(const uint8_t* packet) const {
  PacketHeader h = ReadHeader(packet);
  return FlightShare(h, shape_.empty() ? nullptr : MaskBytes(packet), box_, cell_);
}

// The cosine-weighted share of h's hemisphere whose centre rays are open
// in the packet's mask `bits` (null: no mask, all open) and cross the face
// from h.fromEnv into the receiver's `box` (at grid cell `to`). Worked out
// by the sender (Forward), with the receiver's box as the receiver makes
// it (EnvGrid::EnvBox); every environment has the same tables
// (ExchangeState's directions and flight columns).
double Environment::FlightShare(const PacketHeader& h, const uint8_t* bits, const Bounds& box,
                                const int to[3]) const {
  const uint32_t res = exchange_.flightRes(), cols = 4 * res;
  int from[3];
  envGrid_.Cell(static_cast<int>(h.fromEnv), from);
  int axis = 0;
  for (int a = 0; a < 3; ++a)
    if (from[a] != to[a]) axis = a;
  const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
  const double plane = from[axis] < to[axis] ? box.lo[axis] : box.hi[axis];
  // The centre ray's origin and frame, as Method B casts it.
  Patch shooter = PatchFromHeader(h);
  Frame f = MakePatchSampler(shooter).frame;
  const glm::vec3 centre = MaskCentre(shooter);
  const glm::vec3 o = centre + CentreLift(shooter.globalId) * f.n;
  const double halfPi = 1.5707963267948966;
  const double* colCs = exchange_.flightCols();
  auto isOpen = [bits](uint32_t p) { return !bits || ((bits[p >> 3] >> (p & 7)) & 1u); };
  // Whether the centre direction of (row, col) crosses the face into this box.
  auto crosses = [&](double st, double ct, uint32_t col) {
    double lx = st * colCs[2 * col], ly = st * colCs[2 * col + 1];
    // The crossing axis first: about half the directions point away.
    double dAxis = lx * f.t[axis] + ly * f.b[axis] + ct * f.n[axis];
    if (dAxis == 0.0) return false;
    double t = (plane - o[axis]) / dAxis;
    if (!(t > 0.0)) return false;
    double d1 = lx * f.t[a1] + ly * f.b[a1] + ct * f.n[a1];
    double d2 = lx * f.t[a2] + ly * f.b[a2] + ct * f.n[a2];
    double q1 = o[a1] + t * d1, q2 = o[a2] + t * d2;
    // Half-open, so a direction through an edge enters one box only.
    return q1 >= box.lo[a1] && q1 < box.hi[a1] && q2 >= box.lo[a2] && q2 < box.hi[a2];
  };
  // With a mask, the face's view: only the columns that may see the face
  // are looked at, and of those, the ones surely inside it by far more
  // than the rounding of `crosses` are counted without it (the same count:
  // tests/env_test.cpp).
  PolygonView view;
  const CentreRays rays{o, f, &exchange_.directions()};
  const bool framed =
      bits && exchange_.directions().res() == res &&
      FaceView(BoxFace(box, axis, from[axis] < to[axis] ? 0 : 1), rays, 1e-7, 1e-7, &view);
  double share = 0.0;
  for (uint32_t row = 0; row < res; ++row) {
    double s0 = std::sin(row * halfPi / res), s1 = std::sin((row + 1) * halfPi / res);
    double theta = (row + 0.5) * halfPi / res, st = std::sin(theta), ct = std::cos(theta);
    uint32_t crossing = 0;
    const uint32_t base = row * cols;
    if (framed) {
      PixelArc may, sure;
      if (ViewRow(view, rays, row, &may, &sure))
        ForArc(may, sure, static_cast<int>(cols), [&](int col, bool surely) {
          uint32_t c = static_cast<uint32_t>(col);
          crossing += isOpen(base + c) && (surely || crosses(st, ct, c));
        });
    } else {
      for (uint32_t col = 0; col < cols; ++col) {
        uint32_t p = base + col;
        if (bits) {
          uint8_t byte = bits[p >> 3] >> (p & 7);
          if (byte == 0) {
            col += 7 - (p & 7);  // the rest of this byte is closed
            continue;
          }
          if (!(byte & 1u)) continue;
        }
        crossing += crosses(st, ct, col);
      }
    }
    share += (s1 * s1 - s0 * s0) * crossing / cols;
  }
  return share;
}

}  // namespace vismask
