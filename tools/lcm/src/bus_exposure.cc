// SPDX-License-Identifier: Apache-2.0
#include "rigcal/lcm/bus_exposure.h"

#include <arpa/inet.h>

#include <bitset>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>

namespace rigcal::lcm {
namespace {

constexpr const char* kLcmDefaultUrl = "udpm://239.255.76.67:7667?ttl=0";

struct Route {
  std::string link;
  int prefix = -1;
  long metric = 0;
};

// The route the kernel takes to `address` (network byte order): the longest matching prefix
// among the routes that are up, then the lowest metric. nullopt when none matches or the
// table cannot be read.
std::optional<Route> RouteTo(uint32_t address, const std::string& table) {
  std::ifstream in(table);
  if (!in) return std::nullopt;
  std::string line;
  std::getline(in, line);  // header
  std::optional<Route> best;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string link, destination, gateway, flags, refcnt, use, mask;
    long metric = 0;
    if (!(fields >> link >> destination >> gateway >> flags >> refcnt >> use >> metric >> mask)) {
      continue;
    }
    // Addresses as the kernel prints them: the 32-bit word of the network-order bytes, in hex.
    const uint32_t dest = static_cast<uint32_t>(std::strtoul(destination.c_str(), nullptr, 16));
    const uint32_t netmask = static_cast<uint32_t>(std::strtoul(mask.c_str(), nullptr, 16));
    const unsigned long route_flags = std::strtoul(flags.c_str(), nullptr, 16);
    if ((route_flags & 0x1u) == 0 || (address & netmask) != dest) continue;  // RTF_UP
    const int prefix = static_cast<int>(std::bitset<32>(netmask).count());
    if (!best || prefix > best->prefix || (prefix == best->prefix && metric < best->metric)) {
      best = Route{link, prefix, metric};
    }
  }
  return best;
}

std::string WaysOut(const std::string& what) {
  return what +
         "; keep the bus on this host (udpm:// with ttl=0 and the group routed to lo: ip "
         "route add GROUP/32 dev lo; memq://) or allow the network with --lcm-network";
}

std::string OptionValue(const std::string& options, const std::string& key) {
  std::istringstream in(options);
  std::string pair;
  while (std::getline(in, pair, '&')) {
    const size_t eq = pair.find('=');
    if (eq != std::string::npos && pair.substr(0, eq) == key) return pair.substr(eq + 1);
  }
  return "";
}

}  // namespace

Status CheckBusStaysOnHost(const std::string& given, const std::string& route_table) {
  std::string url = given;
  if (url.empty()) {
    const char* env = std::getenv("LCM_DEFAULT_URL");
    url = env != nullptr && *env != '\0' ? env : kLcmDefaultUrl;
  }
  const std::string name = "LCM URL '" + url + "'";
  const size_t sep = url.find("://");
  if (sep == std::string::npos) return Error{name + ": not PROVIDER://..."};
  const std::string provider = url.substr(0, sep);
  const std::string rest = url.substr(sep + 3);
  if (provider == "memq" || provider == "file") return Status::Ok();
  const size_t question = rest.find('?');
  const std::string address = rest.substr(0, question);
  const std::string options = question == std::string::npos ? "" : rest.substr(question + 1);
  const size_t colon = address.rfind(':');
  const std::string host = colon == std::string::npos ? address : address.substr(0, colon);
  if (provider == "tcpq") {
    in_addr ip{};
    const bool loopback = host == "localhost" || (::inet_pton(AF_INET, host.c_str(), &ip) == 1 &&
                                                  (ntohl(ip.s_addr) >> 24) == 127);
    if (loopback) return Status::Ok();
    return Error{WaysOut(name + ": the server " + host + " is not on this host")};
  }
  if (provider != "udpm") {
    return Error{WaysOut(name + ": cannot tell whether provider '" + provider +
                         "' stays on this host (memq, file, udpm and tcpq are known)")};
  }
  in_addr group{};
  if (host.empty()) {
    ::inet_pton(AF_INET, "239.255.76.67", &group);
  } else if (::inet_pton(AF_INET, host.c_str(), &group) != 1) {
    return Error{name + ": '" + host + "' is not an IPv4 multicast group"};
  }
  const std::string ttl = OptionValue(options, "ttl");
  if (!ttl.empty() && std::strtol(ttl.c_str(), nullptr, 10) != 0) {
    return Error{WaysOut(name + ": ttl=" + ttl + " sends rigcal's messages to other hosts")};
  }
  const std::optional<Route> route = RouteTo(group.s_addr, route_table);
  if (route && route->link != "lo") {
    return Error{WaysOut(name + ": the route to " + (host.empty() ? "239.255.76.67" : host) +
                         " goes through '" + route->link +
                         "', so hosts on that network can send to the group")};
  }
  // No route at all: LCM itself cannot open the bus and says so.
  return Status::Ok();
}

}  // namespace rigcal::lcm
