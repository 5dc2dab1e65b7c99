#pragma once
/// \file
/// The terminal tables of `cairn eval ape|rpe|kitti|relations` (cmd_eval.cpp), on standard
/// output (standard error when --json - claimed it).

#include <cstddef>

#include "cairn/cli/eval_flags.hpp"
#include "cairn/eval/ape.hpp"
#include "cairn/eval/kitti_metric.hpp"
#include "cairn/eval/relations.hpp"
#include "cairn/eval/rpe.hpp"

namespace cairn::cli {

/// Header (relation, inputs), pairs, alignment and statistics.
void print_ape_table(const eval::ApeResult& result, const EvalFlags& flags);
/// As APE's, with the delta and the pair selection in the header.
void print_rpe_table(const eval::RpeResult& result, const eval::RpeOptions& options, const EvalFlags& flags);
/// Pairs, path length, t_err and r_err overall and per nominal length.
void print_kitti_table(const eval::KittiResult& result, const EvalFlags& flags);
/// The four rows of Hess et al. 2016 Table II over `relation_count` relations.
void print_relations_table(const eval::RelationsResult& result, std::size_t relation_count, const EvalFlags& flags);

}  // namespace cairn::cli
