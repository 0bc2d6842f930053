// The suite's main: runs every gtest and ends with the line
// "N passed, N failed" (the project's contract with CI).
#include <gtest/gtest.h>

#include <cstdio>

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  int rc = RUN_ALL_TESTS();
  const testing::UnitTest& u = *testing::UnitTest::GetInstance();
  std::printf("%d passed, %d failed\n", u.successful_test_count(), u.failed_test_count());
  std::fflush(stdout);
  return rc;
}
