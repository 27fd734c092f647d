// SPDX-License-Identifier: Apache-2.0
#include "trajectory_formats.h"

namespace rigcal::io {
namespace internal {
namespace {

// `t tx ty tz qx qy qz qw [segment]`, t in seconds.
constexpr PoseLineFormat kTum = {TrajectoryFormat::kTum,
                                 /*comma_separated=*/false,
                                 /*seconds=*/true,
                                 /*c_cols=*/{1, 2, 3},
                                 /*q_cols=*/{7, 4, 5, 6},
                                 /*segment_column=*/true,
                                 {"t [s]", "tx", "ty", "tz", "qx", "qy", "qz", "qw", "segment"}};

// `t_ns,p_x,p_y,p_z,q_w,q_x,q_y,q_z[,...]`.
constexpr PoseLineFormat kEurocCsv = {
    TrajectoryFormat::kEurocCsv,
    /*comma_separated=*/true,
    /*seconds=*/false,
    /*c_cols=*/{1, 2, 3},
    /*q_cols=*/{4, 5, 6, 7},
    /*segment_column=*/false,
    {"timestamp [ns]", "p_x", "p_y", "p_z", "q_w", "q_x", "q_y", "q_z", nullptr}};

// `t_ns qw qx qy qz Cx Cy Cz [segment]`.
constexpr PoseLineFormat kNative = {TrajectoryFormat::kNative,
                                    /*comma_separated=*/false,
                                    /*seconds=*/false,
                                    /*c_cols=*/{5, 6, 7},
                                    /*q_cols=*/{1, 2, 3, 4},
                                    /*segment_column=*/true,
                                    {"t_ns", "qw", "qx", "qy", "qz", "Cx", "Cy", "Cz", "segment"}};

}  // namespace

const PoseLineFormat& LineFormatOf(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return kTum;
    case TrajectoryFormat::kEurocCsv:
      return kEurocCsv;
    case TrajectoryFormat::kNative:
      return kNative;
  }
  return kTum;
}

TrajectoryFormat DetectFormat(std::string_view first_data_line, bool native_header) {
  if (first_data_line.find(',') != std::string_view::npos) return TrajectoryFormat::kEurocCsv;
  if (native_header) return TrajectoryFormat::kNative;
  const auto fields = SplitWhitespace(first_data_line);
  if (!fields.empty() && IsPlainInteger(fields[0])) {
    const auto t = ParseInteger<int64_t>(fields[0]);
    if (t && (*t >= 1'000'000'000'000LL || *t <= -1'000'000'000'000LL)) {
      return TrajectoryFormat::kNative;
    }
  }
  return TrajectoryFormat::kTum;
}

Expected<ParsedLine> ParseFields(const std::vector<std::string_view>& fields,
                                 const PoseLineFormat& format, const LineParser& p) {
  ParsedLine out;
  constexpr int t_col = 0;
  auto t = format.seconds ? p.SecondsStamp(fields[t_col], t_col)
                          : p.NanosecondStamp(fields[t_col], t_col);
  if (!t) return Error{t.error()};
  out.t_ns = *t;
  for (int i = 0; i < 3; ++i) {
    auto v = p.Number(fields[format.c_cols[i]], format.c_cols[i]);
    if (!v) return Error{v.error()};
    out.c[i] = *v;
  }
  for (int i = 0; i < 4; ++i) {
    auto v = p.Number(fields[format.q_cols[i]], format.q_cols[i]);
    if (!v) return Error{v.error()};
    out.q_wxyz[i] = *v;
  }
  if (format.segment_column && fields.size() > kPoseColumns) {
    auto s = p.Segment(fields[kPoseColumns], kPoseColumns);
    if (!s) return Error{s.error()};
    out.segment = *s;
  }
  return out;
}

}  // namespace internal

std::string ToString(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return "TUM";
    case TrajectoryFormat::kEurocCsv:
      return "EuRoC CSV";
    case TrajectoryFormat::kNative:
      return "rigcal native";
  }
  return "unknown";
}

}  // namespace rigcal::io
