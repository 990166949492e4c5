/* C entry points of the dataset reader (dataset.h) for callers that load the library without
 * C++ bindings, e.g. Python's ctypes in the ROS dataset player: the one SemanticKITTI-layout
 * reader, with its poses T_W_S = inv(Tr) P Tr, its no-return filter and its label checks. */
#ifndef EVIDENTIAL_OCTOMAP_DATASET_C_H
#define EVIDENTIAL_OCTOMAP_DATASET_C_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct evidential_octomap_dataset evidential_octomap_dataset;

/* Opens a dataset directory (or one .bin scan) with its class table YAML. Returns NULL and a
 * message (at most error_size bytes, NUL-terminated) in error when it cannot be read. */
evidential_octomap_dataset* evidential_octomap_dataset_open(const char* path,
                                                            const char* class_table,
                                                            char* error, size_t error_size);
void evidential_octomap_dataset_close(evidential_octomap_dataset* dataset);
size_t evidential_octomap_dataset_size(const evidential_octomap_dataset* dataset);

/* Reads scan i, which becomes the dataset's current scan, with the classes of its
 * "predictions" or "labels" files. Returns its number of points, or -1 and a message. */
long long evidential_octomap_dataset_load(evidential_octomap_dataset* dataset, size_t i,
                                          const char* classes_from, char* error,
                                          size_t error_size);

/* Copies the current scan: xyz (n x 3, sensor frame), remission (n), classes (n), the pose
 * T_W_S (16 doubles, row-major) and the scan's name (at most name_size bytes, NUL-terminated).
 * Any output may be NULL. */
void evidential_octomap_dataset_scan(const evidential_octomap_dataset* dataset, float* xyz,
                                     float* remission, int32_t* classes, double* pose,
                                     char* name, size_t name_size);

#ifdef __cplusplus
}
#endif

#endif
