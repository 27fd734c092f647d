// SPDX-License-Identifier: Apache-2.0
// CheckBusStaysOnHost: which LCM URLs keep rigcal's bus on this host, against routing tables in
// the format of /proc/net/route (the kernel's hex words of network-order addresses). The URLs
// are only parsed: no LCM bus is opened and no socket is made, so no namespace is needed (the
// live refusals run in lcm/lcm_udpm_netns, inside a private network namespace).
#include "rigcal/lcm/bus_exposure.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <string>

#include "support/temp_dir.h"

namespace rigcal::lcm {
namespace {

using ::testing::HasSubstr;

constexpr const char* kHeader =
    "Iface\tDestination\tGateway \tFlags\tRefCnt\tUse\tMetric\tMask\t\tMTU\tWindow\tIRTT\n";
// A default route through eth0 (gateway 192.168.0.1) and its /24.
constexpr const char* kDefaultViaEth0 =
    "eth0\t00000000\t0100A8C0\t0003\t0\t0\t0\t00000000\t0\t0\t0\n"
    "eth0\t0000A8C0\t00000000\t0001\t0\t0\t0\t00FFFFFF\t0\t0\t0\n";
// 224.0.0.0/4 on lo (the private namespaces of the tests; docs/architecture.md "LCM").
constexpr const char* kMulticastOnLo = "lo\t000000E0\t00000000\t0001\t0\t0\t0\t000000F0\t0\t0\t0\n";
// 239.255.76.67/32 on lo.
constexpr const char* kGroupOnLo = "lo\t434CFFEF\t00000000\t0005\t0\t0\t0\tFFFFFFFF\t0\t0\t0\n";

class BusExposure : public ::testing::Test {
 protected:
  std::string Table(const std::string& routes) {
    const std::string path = (dir_ / ("route" + std::to_string(++n_))).string();
    std::ofstream(path) << kHeader << routes;
    return path;
  }
  std::filesystem::path dir_ = support::FreshTempDir("bus_exposure");
  int n_ = 0;
};

TEST_F(BusExposure, InProcessAndFilesStayOnHost) {
  const std::string eth0 = Table(kDefaultViaEth0);
  EXPECT_TRUE(CheckBusStaysOnHost("memq://", eth0).ok());
  EXPECT_TRUE(CheckBusStaysOnHost("file:///tmp/x.lcmlog?mode=w", eth0).ok());
}

TEST_F(BusExposure, MulticastThroughANetworkLinkIsRefused) {
  const Status s = CheckBusStaysOnHost("udpm://239.255.76.67:7667?ttl=0", Table(kDefaultViaEth0));
  ASSERT_FALSE(s.ok());
  EXPECT_THAT(s.message(), HasSubstr("udpm://239.255.76.67:7667?ttl=0"));
  EXPECT_THAT(s.message(), HasSubstr("goes through 'eth0'"));
  EXPECT_THAT(s.message(), HasSubstr("--lcm-network"));
  EXPECT_THAT(s.message(), HasSubstr("dev lo"));
}

TEST_F(BusExposure, MulticastRoutedToLoopbackStaysOnHost) {
  EXPECT_TRUE(CheckBusStaysOnHost("udpm://239.255.76.67:7667?ttl=0",
                                  Table(std::string(kDefaultViaEth0) + kMulticastOnLo))
                  .ok());
  // The longest prefix wins: a /32 on lo beats a /4 elsewhere, and the other way round.
  const std::string group_on_lo =
      Table(std::string(kDefaultViaEth0) + "eth0\t000000E0\t00000000\t0001\t0\t0\t0\t000000F0"
                                           "\t0\t0\t0\n" +
            kGroupOnLo);
  EXPECT_TRUE(CheckBusStaysOnHost("udpm://239.255.76.67:7667", group_on_lo).ok());
  EXPECT_FALSE(CheckBusStaysOnHost("udpm://239.255.76.68:7667", group_on_lo).ok());
  // A route that is down (flags without RTF_UP) is not taken.
  const std::string down = Table(std::string(kDefaultViaEth0) +
                                 "lo\t000000E0\t00000000\t0000\t0\t0\t0\t000000F0\t0\t0\t0\n");
  EXPECT_FALSE(CheckBusStaysOnHost("udpm://239.255.76.67:7667", down).ok());
}

TEST_F(BusExposure, TtlAboveZeroIsRefusedEvenOnLoopback) {
  const Status s = CheckBusStaysOnHost("udpm://239.255.76.67:7667?recv_buf_size=1000&ttl=1",
                                       Table(kMulticastOnLo));
  ASSERT_FALSE(s.ok());
  EXPECT_THAT(s.message(), HasSubstr("ttl=1"));
}

TEST_F(BusExposure, DefaultUrlIsLcmsDefault) {
  ::unsetenv("LCM_DEFAULT_URL");
  const Status s = CheckBusStaysOnHost("", Table(kDefaultViaEth0));
  ASSERT_FALSE(s.ok());
  EXPECT_THAT(s.message(), HasSubstr("udpm://239.255.76.67:7667?ttl=0"));
  ::setenv("LCM_DEFAULT_URL", "memq://", 1);
  EXPECT_TRUE(CheckBusStaysOnHost("", Table(kDefaultViaEth0)).ok());
  ::unsetenv("LCM_DEFAULT_URL");
}

TEST_F(BusExposure, TcpServerMustBeLocal) {
  const std::string table = Table(kDefaultViaEth0);
  EXPECT_TRUE(CheckBusStaysOnHost("tcpq://127.0.0.1:7700", table).ok());
  EXPECT_TRUE(CheckBusStaysOnHost("tcpq://localhost:7700", table).ok());
  const Status s = CheckBusStaysOnHost("tcpq://10.1.2.3:7700", table);
  ASSERT_FALSE(s.ok());
  EXPECT_THAT(s.message(), HasSubstr("10.1.2.3 is not on this host"));
}

TEST_F(BusExposure, UnreadableUrlsAreErrorsNamingThem) {
  const std::string table = Table(kMulticastOnLo);
  EXPECT_THAT(CheckBusStaysOnHost("nonsense", table).message(), HasSubstr("'nonsense'"));
  EXPECT_THAT(CheckBusStaysOnHost("udpm://not-an-ip:7667", table).message(),
              HasSubstr("'not-an-ip' is not an IPv4 multicast group"));
  EXPECT_THAT(CheckBusStaysOnHost("mpudpm://239.255.76.67:7667", table).message(),
              HasSubstr("cannot tell whether provider 'mpudpm'"));
}

}  // namespace
}  // namespace rigcal::lcm
