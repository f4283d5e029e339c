// Libraries opened at run time (src/hof/core/shared_library.cpp), as the device SDKs are: the
// first name the loader finds wins, a function is found and called through its address, and a
// missing library or function is an error naming every name tried, where the loader looked,
// how to install it, and the symbol.

#include "hof/core/shared_library.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace hof {
namespace {

// The C maths library: present wherever HoF runs (HoF itself links it).
const std::string kLibm = "libm.so.6";

TEST(SharedLibrary, OpensTheFirstNameFoundAndCallsAFunctionInIt) {
  const std::vector<std::string> names{"libhof-no-such-sdk.so.3", kLibm};
  auto library = SharedLibrary::open(names, "the maths library", "");
  ASSERT_TRUE(library) << library.error().to_string();
  EXPECT_NE(library->path().find("libm"), std::string::npos) << library->path();
  const auto cosine = library->function<double(double)>("cos");
  ASSERT_TRUE(cosine) << cosine.error().to_string();
  EXPECT_EQ((*cosine)(0.0), 1.0);
  double (*slot)(double) = nullptr;
  ASSERT_TRUE(library->bind("sqrt", slot));
  EXPECT_EQ(slot(2.25), 1.5);
}

TEST(SharedLibrary, AMissingLibraryNamesEveryNameTriedWhereAndHowToInstall) {
  const std::vector<std::string> names{"libhof-no-such-sdk.so.3", "/nowhere/libhof-sdk.so"};
  const auto library = SharedLibrary::open(names, "the Example SDK", "Install it from example.com.");
  ASSERT_FALSE(library);
  EXPECT_EQ(library.error().code, ErrorCode::kIo);
  const std::string text = library.error().to_string();
  EXPECT_NE(text.find("the Example SDK is not installed or not found"), std::string::npos) << text;
  EXPECT_NE(text.find("libhof-no-such-sdk.so.3 ("), std::string::npos) << text;
  EXPECT_NE(text.find("; /nowhere/libhof-sdk.so ("), std::string::npos) << text;
  EXPECT_NE(text.find("the loader cache (ldconfig -p)"), std::string::npos) << text;
  EXPECT_NE(text.find("Install it from example.com."), std::string::npos) << text;
  // The loader's reason follows each name, not the name a second time.
  EXPECT_EQ(text.find("libhof-no-such-sdk.so.3: "), std::string::npos) << text;
}

TEST(SharedLibrary, AMissingFunctionNamesTheSymbolAndTheLibraryAndBindOptionalGivesNull) {
  const std::vector<std::string> names{kLibm};
  auto library = SharedLibrary::open(names, "the maths library", "");
  ASSERT_TRUE(library);
  const auto missing = library->function<void()>("hofNoSuchFunction");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::kUnsupported);
  EXPECT_NE(missing.error().to_string().find("no function 'hofNoSuchFunction'"), std::string::npos);
  EXPECT_NE(missing.error().to_string().find("libm"), std::string::npos);
  void (*slot)() = reinterpret_cast<void (*)()>(&std::abort);
  library->bind_optional("hofNoSuchFunction", slot);
  EXPECT_EQ(slot, nullptr);
  EXPECT_FALSE(library->bind("hofNoSuchFunction", slot));
}

TEST(SharedLibrary, NoNamesIsAnErrorToo) {
  const auto library = SharedLibrary::open({}, "the Example SDK", "");
  ASSERT_FALSE(library);
  EXPECT_EQ(library.error().code, ErrorCode::kIo);
}

}  // namespace
}  // namespace hof
