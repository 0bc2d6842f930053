#include "vismask/app/app.h"
#include "vismask/core/os.h"

int main(int argc, char** argv) {
  vismask::os::GuardStandardDescriptors();
  return vismask::Main(argc, argv);
}
