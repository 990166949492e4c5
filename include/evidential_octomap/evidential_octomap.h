// Everything a user of the map library needs, in one include (as octomap/octomap.h is for
// OctoMap): the tree and its settings, the fusion rules' read-out, files, class tables and the
// evidence conversions. The evaluation/ and evidence/ headers belong to libraries of their own
// (evidential_octomap::evaluation, evidential_octomap::evidence) and are included on their own.
#pragma once

#include <octomap/octomap.h>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/fusion_rule.h"
#include "evidential_octomap/io.h"
#include "evidential_octomap/semantic_config.h"
#include "evidential_octomap/sensor_model.h"
#include "evidential_octomap/settings.h"
#include "evidential_octomap/subjective_logic.h"
