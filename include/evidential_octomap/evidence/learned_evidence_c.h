/* C entry point of the learned evidence head (learned_evidence.h) for callers that load the
 * library without C++ bindings, e.g. Python's ctypes in the ROS dataset player. */
#ifndef EVIDENTIAL_OCTOMAP_LEARNED_EVIDENCE_C_H
#define EVIDENTIAL_OCTOMAP_LEARNED_EVIDENCE_C_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Evidence (n x num_classes, row-major, written to evidence_out) of one scan: xyz n x 3 in the
 * sensor frame, remission n values (or NULL), predicted n class ids (-1: none). Only the model's
 * folds that were not trained on this scan are used. Returns 0 on success; otherwise a non-zero
 * value and a message (at most error_size bytes, NUL-terminated) in error. */
int evidential_octomap_learned_evidence(const char* model_path, const float* xyz,
                                        const float* remission, const int32_t* predicted,
                                        size_t n, int num_classes, float* evidence_out,
                                        char* error, size_t error_size);

#ifdef __cplusplus
}
#endif

#endif
