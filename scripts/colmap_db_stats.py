#!/usr/bin/env python3
"""Features per image and matches per pair in a COLMAP database: python3 scripts/colmap_db_stats.py DATABASE.db [--json].
keypoints.rows = SIFT features kept per image; matches.rows = descriptor matches of a pair (ratio test and cross
check); two_view_geometries.rows = the matches the geometric verification kept (inliers), config >= 2 = a
verified pair. How docs/benchmarks.md ("How fast COLMAP can be") counts them."""
import json, sqlite3, statistics, sys


def summary(values):
    if not values:
        return {"count": 0, "mean": 0, "median": 0, "min": 0, "max": 0}
    return {"count": len(values), "mean": round(statistics.mean(values), 1), "median": statistics.median(values),
            "min": min(values), "max": max(values)}


def main():
    db = sqlite3.connect(sys.argv[1])
    features = [r[0] for r in db.execute("SELECT rows FROM keypoints")]
    pairs = [r[0] for r in db.execute("SELECT rows FROM matches")]
    verified = [r[0] for r in db.execute("SELECT rows FROM two_view_geometries WHERE config >= 2 AND rows > 0")]
    out = {"features_per_image": summary(features), "matches_per_pair": summary(pairs),
           "inliers_per_verified_pair": summary(verified)}
    if "--json" in sys.argv:
        print(json.dumps(out))
        return
    f, m, v = out["features_per_image"], out["matches_per_pair"], out["inliers_per_verified_pair"]
    print(f"images {f['count']}: features per image mean {f['mean']} median {f['median']} (min {f['min']}, max {f['max']})")
    print(f"pairs matched {m['count']}: matches per pair mean {m['mean']} median {m['median']} (max {m['max']})")
    print(f"pairs verified {v['count']}: inliers per pair mean {v['mean']} median {v['median']} (max {v['max']})")


if __name__ == "__main__":
    main()
