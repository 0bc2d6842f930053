#include "vismask/app.h"
#include "vismask/os.h"

int main(int argc, char** argv) {
  vismask::os::GuardStandardDescriptors();
  return vismask::Main(argc, argv);
}
