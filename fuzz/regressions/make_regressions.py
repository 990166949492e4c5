#!/usr/bin/env python3
"""Re-creates the hand-reduced regression inputs in ot/ from the seed corpus.

   python3 fuzz/regressions/make_regressions.py <seed_dir>/ot fuzz/regressions/ot

Each input is a seed .ot written by the library (make_seeds) with one field changed, i.e. the
smallest form of a crash the fuzzers found. See README.md beside this file for what each broke.
"""
import struct
import sys


def data_offset(b):
    return b.index(b"\ndata\n") + 6


def header_fields(b):
    """Offsets of the semantic header's fields (see EvidentialOcTree::writeData)."""
    at = data_offset(b)
    fields = {"magic": at}
    at += 8
    (num_classes,) = struct.unpack_from("<I", b, at)
    fields["num_classes"] = at
    at += 4
    for _ in range(num_classes):
        (n,) = struct.unpack_from("<I", b, at)
        at += 4 + n
    (n,) = struct.unpack_from("<I", b, at)
    at += 4 + n
    for name in ("length_scale", "sigma0", "beta", "gamma", "drop_percent", "ds_multiplier",
                 "max_range"):
        fields[name] = at
        at += 8
    at += 5  # flags
    fields["sbki_prior"] = at
    at += 4 + 5 * 4
    fields["node_count"] = at
    at += 8
    fields["root"] = at  # float log-odds, u8 children, u8 has_payload, [C floats]
    fields["C"] = num_classes
    return fields


def first_leaf_payload(b, f):
    """Offset of the payload of the first leaf that has one (nodes are stored in pre-order)."""
    at = f["root"]
    while True:
        children, has = b[at + 4], b[at + 5]
        if has and children == 0:
            return at + 6
        at += 6 + (4 * f["C"] if has else 0)


def main():
    seeds, out = sys.argv[1], sys.argv[2]
    dempster = bytearray(open(seeds + "/dempster_c1.ot", "rb").read())
    f = header_fields(dempster)
    dempster3 = bytearray(open(seeds + "/dempster_c3.ot", "rb").read())
    f3 = header_fields(dempster3)

    b = bytearray(dempster3)  # Dempster L < 0 beside L > 0: accepted, reads out as NaN
    at = first_leaf_payload(b, f3)
    struct.pack_into("<fff", b, at, -1e30, 2.0, 1.0)
    open(out + "/negative_payload.ot", "wb").write(b)

    b = bytearray(dempster)  # L = FLT_MAX in a leaf: merge() adds two of them to inf, then NaN
    struct.pack_into("<f", b, first_leaf_payload(b, f), 3.4028234e38)
    open(out + "/payload_flt_max_merge.ot", "wb").write(b)

    b = bytearray(dempster)  # ds_multiplier 1e300: int64 cast of inf in downsample() (UB)
    struct.pack_into("<d", b, f["ds_multiplier"], 1e300)
    open(out + "/ds_multiplier_1e300.ot", "wb").write(b)

    # res 1e300: leaf coordinates overflow float, OctoMap's coordToKeyChecked casts inf to int
    b = bytes(dempster).replace(b"\nres 0.5\n", b"\nres 1e300\n")
    open(out + "/resolution_1e300.ot", "wb").write(b)

    # A foreign OcTree whose nodes form a 300000-deep chain: OctoMap's OcTree reader recurses
    # without a depth limit; loadMap handed it the data and overflowed the stack.
    n = 300000
    header = b"# Octomap OcTree file\n# deep chain\nid OcTree\nsize %d\nres 0.1\ndata\n" % n
    open(out + "/foreign_octree_deep_chain.ot", "wb").write(
        header + (struct.pack("<f", 0.5) + b"\x01") * n)


if __name__ == "__main__":
    main()
