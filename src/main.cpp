#include "vismask/app.h"

int main(int argc, char** argv) { return vismask::Main(argc, argv); }
