#!/usr/bin/env python3
"""Builds the labelled real-texture set (issue 12) from Debian-packaged game texture data.

Reads bench/realset/labels.json, fetches each package it names with `apt-get download` (the .deb is
only unpacked into the cache with `dpkg-deb -x`, nothing is installed), takes each image out of the
package (a path `A.pk3!B` means member B of the zip archive A), and writes it as an 8-bit RGB PNG at
its native resolution, cropped to a square: the item's "crop" [x, y, side] when given, otherwise
the centred square of side min(width, height, 512). Nothing is rescaled.

Output (default build/realset):
  images/<id>.png      one per labelled item
  manifest.json        id -> png path, sha256, source size, crop, package version
  debs/, pkgs/, src/   download and extraction cache (delete to refetch)

Idempotent: images that already exist with the recorded crop are kept; --force rebuilds them.
Needs: python3, apt-get + dpkg-deb (Debian), oiiotool (openimageio-tools).
"""
import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))


def die(msg, hint):
    print(f"realset: error: {msg} ({hint})", file=sys.stderr)
    sys.exit(1)


def run(cmd, **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        die(f"{' '.join(cmd)} failed: {r.stderr.strip()[-400:]}", "see the message above")
    return r.stdout


def fetch_package(pkg, out):
    """Downloads and unpacks one package into out/pkgs/<pkg>; returns (root, version)."""
    root = os.path.join(out, "pkgs", pkg)
    stamp = os.path.join(root, ".version")
    if os.path.exists(stamp):
        return root, open(stamp).read().strip()
    debs = os.path.join(out, "debs")
    os.makedirs(debs, exist_ok=True)
    have = [f for f in os.listdir(debs) if f.startswith(pkg + "_") and f.endswith(".deb")]
    if not have:
        print(f"realset: apt-get download {pkg}", file=sys.stderr)
        run(["apt-get", "download", pkg], cwd=debs)
        have = [f for f in os.listdir(debs) if f.startswith(pkg + "_") and f.endswith(".deb")]
        if not have:
            die(f"apt-get download {pkg} left no .deb", "run apt-get update, check the package name")
    deb = os.path.join(debs, sorted(have)[-1])
    version = run(["dpkg-deb", "-f", deb, "Version"]).strip()
    tmp = root + ".tmp"
    os.makedirs(os.path.dirname(root), exist_ok=True)
    if os.path.exists(tmp):
        run(["rm", "-rf", tmp])
    print(f"realset: unpacking {os.path.basename(deb)}", file=sys.stderr)
    run(["dpkg-deb", "-x", deb, tmp])
    with open(os.path.join(tmp, ".version"), "w") as f:
        f.write(version + "\n")
    if os.path.exists(root):  # an unpack without a stamp: incomplete
        run(["rm", "-rf", root])
    os.rename(tmp, root)
    return root, version


def source_file(item, root, out):
    """Returns a file path holding the item's original image (extracting a zip member if needed)."""
    path = item["path"]
    if "!" not in path:
        src = os.path.join(root, path)
        if not os.path.exists(src):
            die(f"{item['id']}: {path} not in package {item['package']}", "package version changed?")
        return src
    archive, member = path.split("!", 1)
    ext = os.path.splitext(member)[1].lower()
    src = os.path.join(out, "src", item["id"] + ext)
    if os.path.exists(src):
        return src
    os.makedirs(os.path.dirname(src), exist_ok=True)
    try:
        with zipfile.ZipFile(os.path.join(root, archive)) as z:
            data = z.read(member)
    except (KeyError, OSError, zipfile.BadZipFile) as e:
        die(f"{item['id']}: cannot read {member} from {archive}: {e}", "package version changed?")
    with open(src + ".tmp", "wb") as f:
        f.write(data)
    os.rename(src + ".tmp", src)
    return src


def image_info(src):
    """(width, height, channels) of an image file, read by oiiotool."""
    line = run(["oiiotool", "--info", src]).splitlines()[0]
    # "<file> :  512 x  512, 3 channel, uint8 png"
    dims = line.split(" : ", 1)[1].split(",")
    w, h = (int(v) for v in dims[0].split("x"))
    ch = int(dims[1].split()[0])
    return w, h, ch


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--labels", default=os.path.join(HERE, "labels.json"), help="labels file (JSON)")
    ap.add_argument("--out", default="build/realset", help="cache and output folder")
    ap.add_argument("--force", action="store_true", help="rebuild every image")
    ap.add_argument("--only", nargs="*", help="build only these ids")
    ap.add_argument("--split", choices=["tune", "report"], help="build only this split (make bench needs only report)")
    args = ap.parse_args()

    try:
        labels = json.load(open(args.labels))
    except (OSError, ValueError) as e:
        die(f"cannot read {args.labels}: {e}", "give --labels bench/realset/labels.json")
    items = labels["images"]
    if args.only:
        items = [i for i in items if i["id"] in set(args.only)]
    if args.split:
        items = [i for i in items if i["split"] == args.split]
    out = args.out
    images = os.path.join(out, "images")
    os.makedirs(images, exist_ok=True)
    manifest_path = os.path.join(out, "manifest.json")
    manifest = {}
    if os.path.exists(manifest_path):
        try:
            manifest = json.load(open(manifest_path))
        except ValueError:
            manifest = {}

    versions = {}
    built = kept = mismatched = 0
    for n, item in enumerate(items, 1):
        pkg = item["package"]
        if pkg not in versions:
            versions[pkg] = fetch_package(pkg, out)
        root, version = versions[pkg]
        if item.get("version") and item["version"] != version:
            print(f"realset: warning: {pkg} is {version}, labels were made from {item['version']}",
                  file=sys.stderr)
        png = os.path.join(images, item["id"] + ".png")
        old = manifest.get(item["id"])
        if (not args.force and old and os.path.exists(png) and old.get("crop") == item.get("crop", old.get("crop"))
                and old.get("sha256") == sha256(png)):
            kept += 1
            continue
        src = source_file(item, root, out)
        w, h, ch = image_info(src)
        if "crop" in item:
            x, y, side = item["crop"]
        else:
            side = min(w, h, 512)
            x, y = (w - side) // 2, (h - side) // 2
        if side < 256 or x < 0 or y < 0 or x + side > w or y + side > h:
            die(f"{item['id']}: crop {x},{y},{side} does not fit {w}x{h} or is under 256 px", "fix labels.json")
        chans = "R,G,B" if ch >= 3 else "0,0,0"
        fd, tmp = tempfile.mkstemp(suffix=".png", dir=images)
        os.close(fd)
        run(["oiiotool", "--nosoftwareattrib", src, "--ch", chans, "--cut", f"{side}x{side}+{x}+{y}", "-d", "uint8", "-o", tmp])
        os.replace(tmp, png)
        digest = sha256(png)
        if item.get("sha256") and item["sha256"] != digest:
            mismatched += 1
            print(f"realset: warning: {item['id']}: the built image differs from the labelled one (sha256)",
                  file=sys.stderr)
        manifest[item["id"]] = {"png": os.path.relpath(png, out), "sha256": digest, "source_size": [w, h],
                                "crop": [x, y, side], "package_version": version}
        built += 1
        print(f"realset: [{n}/{len(items)}] {item['id']} {w}x{h} -> {side}px", file=sys.stderr)
    if not args.only and not args.split:  # drop images of items no longer in the labels
        ids = {i["id"] for i in items}
        for stale in [k for k in manifest if k not in ids]:
            manifest.pop(stale)
        for f in os.listdir(images):
            if f.endswith(".png") and f[:-4] not in ids:
                os.remove(os.path.join(images, f))
    with open(manifest_path + ".tmp", "w") as f:
        json.dump(manifest, f, indent=1, sort_keys=True)
    os.replace(manifest_path + ".tmp", manifest_path)
    print(f"realset: {built} built, {kept} up to date, images in {images}", file=sys.stderr)
    if mismatched:
        print(f"realset: warning: {mismatched} images differ from the labelled ones (other package or tool "
              "versions): check them before comparing numbers", file=sys.stderr)


if __name__ == "__main__":
    main()
