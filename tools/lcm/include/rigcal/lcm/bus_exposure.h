// SPDX-License-Identifier: Apache-2.0
#pragma once
// Whether an LCM URL keeps rigcal's bus on this host. A live calibrator that listens on a bus
// other hosts reach accepts poses from them (and sends them its results), so rigcal's listeners
// (`calib`, `run --lcm`, `status`) stay on loopback unless told otherwise (--lcm-network):
//   memq://, file://          in-process or a file: on this host;
//   udpm://GROUP:PORT?ttl=T   on this host when T = 0 (sent datagrams do not leave it) and the
//                             route to GROUP goes through the loopback link (`ip route add
//                             GROUP/32 dev lo`): otherwise other hosts can send to the group;
//   tcpq://HOST:PORT          on this host when HOST is a loopback address or "localhost".
// An empty URL is LCM's default: $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0.

#include <string>

#include "rigcal/base/status.h"

namespace rigcal::lcm {

// Ok when `url` stays on this host; else the error names the URL, what reaches beyond the host
// (the TTL, the link the route goes through, the host) and the two ways out: a loopback route,
// or --lcm-network. A URL it cannot read, or of another provider, is an error naming the URL.
// Call it on a URL LCM has opened (so LCM's own message tells a URL it cannot open).
// `route_table`: the IPv4 routing table in the format of /proc/net/route (tests give their own).
Status CheckBusStaysOnHost(const std::string& url,
                           const std::string& route_table = "/proc/net/route");

}  // namespace rigcal::lcm
