// libFuzzer target for the image readers (`make fuzz`): the PFM reader of
// `vismask compare` and `render --reference`, and the PGM reader of
// `--exclude`. An input is a file's bytes; each reader gets it (their magic
// numbers differ, so at most one accepts it). A reader must return a Status
// for anything: no crash, no sanitizer report, no hang, no allocation the
// bytes do not justify; and what it accepts is a whole, finite image.
// tests/fuzz/image-corpus/ holds the seeds: small PFMs in both byte orders
// and PGMs.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "vismask/output/image_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  vismask::PfmImage pfm;
  vismask::Status s = vismask::ReadPfmFromBytes("fuzz.pfm", bytes, &pfm);
  (void)s.ToString();
  if (s.ok()) {
    // Accepted: the pixels the header promised, each finite, within the bytes given.
    if (pfm.width <= 0 || pfm.height <= 0 ||
        pfm.pixels.size() != size_t(pfm.width) * size_t(pfm.height) * 3 ||
        pfm.pixels.size() * 4 > size)
      __builtin_trap();
    for (float f : pfm.pixels)
      if (!std::isfinite(f)) __builtin_trap();
  }
  vismask::PgmImage pgm;
  s = vismask::ReadPgmFromBytes("fuzz.pgm", bytes, &pgm);
  (void)s.ToString();
  if (s.ok() &&
      (pgm.width <= 0 || pgm.height <= 0 ||
       pgm.pixels.size() != size_t(pgm.width) * size_t(pgm.height) || pgm.pixels.size() > size))
    __builtin_trap();
  return 0;
}
