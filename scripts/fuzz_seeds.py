#!/usr/bin/env python3
"""Builds the seed corpora of the fuzz targets (fuzz/targets/) from multicue's own outputs, the
small shared scans and meshes, and a few hand-written files that reach rarer header forms.

    scripts/fuzz_seeds.py [--cli build/multicue] [--data ../shared/data] [--out build-fuzz/seeds]

Writes OUT/<target>/<name> for every target; nothing is committed (the corpora are rebuilt from
the CLI in about a minute). Container files (datasets, models, transforms, ensembles, part-graph
models) are stored as their payload: the fuzz targets wrap the input in a valid header and
checksum, so the fuzzer mutates what the decoders read.
"""

import argparse
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MAX_SEED = 256 * 1024  # bytes; larger files slow every execution down
CONTAINER_HEADER = 8 + 4 + 4 + 8 + 4


def run(cli, *args, cwd=None):
    subprocess.run([str(cli), "--threads", "1", *map(str, args)], check=True, cwd=cwd,
                   stdout=subprocess.DEVNULL)


class Seeds:
    def __init__(self, out):
        self.out = Path(out)
        self.count = {}

    def add(self, target, name, data):
        if isinstance(data, str):
            data = data.encode()
        if len(data) > MAX_SEED:
            return
        d = self.out / target
        d.mkdir(parents=True, exist_ok=True)
        (d / name).write_bytes(data)
        self.count[target] = self.count.get(target, 0) + 1

    def add_file(self, target, path, name=None, prefix=b""):
        path = Path(path)
        if path.is_file():
            self.add(target, name or path.name, prefix + path.read_bytes())

    def add_payload(self, target, path, name=None):
        """A container file's payload (the fuzz target adds the header)."""
        path = Path(path)
        if path.is_file():
            self.add(target, name or path.name, path.read_bytes()[CONTAINER_HEADER:])


def tiny_pcds():
    """Small PCD files with the field types, counts, padding and layouts PCL writes."""
    files = {}
    files["organized_nan.pcd"] = (
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\n"
        "SIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 3\nHEIGHT 2\n"
        "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 6\nDATA ascii\n"
        "0 0 1 4278190335\nnan nan nan 0\n0.1 0 1 4294967295\n0 0.1 1 255\n"
        "0.1 0.1 1 65280\nnan nan nan 0\n")
    files["fields_v06.pcd"] = (
        "VERSION .6\nFIELDS x y z normal_x normal_y normal_z curvature label intensity\n"
        "SIZE 4 4 4 4 4 4 4 4 4\nTYPE F F F F F F F U F\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n"
        "DATA ascii\n1 2 3 0 0 1 0.1 7 0.5\n4 5 6 0 1 0 0.2 8 0.25\n")
    files["histogram_count.pcd"] = (
        "VERSION 0.7\nFIELDS x y z fpfh\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 4\n"
        "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n0 0 0 1 2 3 4\n1 1 1 5 6 7 8\n")
    # Binary with '_' padding and every scalar type.
    header = ("VERSION 0.7\nFIELDS x y z _ label i8 u16 d\nSIZE 4 4 4 1 4 1 2 8\n"
              "TYPE F F F U U I U F\nCOUNT 1 1 1 3 1 1 1 1\nWIDTH 2\nHEIGHT 1\n"
              "VIEWPOINT 1 2 3 0.707 0 0.707 0\nPOINTS 2\nDATA binary\n")
    body = b""
    for i in range(2):
        body += struct.pack("<fff3sIbHd", i, 2.0 * i, 3.0, b"\0\0\0", 20 + i, -i, 300 + i, 0.5)
    files["binary_padding.pcd"] = header.encode() + body
    # binary_compressed: sizes then LZF data; a literal-only LZF stream is valid.
    planes = struct.pack("<3f", 0.0, 1.0, 2.0) + struct.pack("<3f", 0.5, 0.5, 0.5) + \
        struct.pack("<3f", 1.0, 1.0, 1.0)
    lzf = b""
    for i in range(0, len(planes), 32):
        chunk = planes[i:i + 32]
        lzf += bytes([len(chunk) - 1]) + chunk
    header = ("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\n"
              "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA binary_compressed\n")
    files["literal_lzf.pcd"] = header.encode() + struct.pack("<II", len(lzf), len(planes)) + lzf
    return files


def tiny_plys():
    files = {}
    files["ascii_mesh.ply"] = (
        "ply\nformat ascii 1.0\ncomment a quad\nelement vertex 4\nproperty float x\n"
        "property float y\nproperty float z\nproperty float nx\nproperty float ny\n"
        "property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
        "property uchar alpha\nproperty uint label\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n"
        "0 0 0 0 0 1 255 0 0 255 1\n1 0 0 0 0 1 0 255 0 255 1\n1 1 0 0 0 1 0 0 255 128 2\n"
        "0 1 0 0 0 1 9 9 9 0 2\n4 0 1 2 3\n")
    header = ("ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\n"
              "property double y\nproperty double z\nproperty float intensity\n"
              "property list uchar float extra\nelement face 1\n"
              "property list uchar uint vertex_index\nelement material 1\nproperty int id\n"
              "end_header\n")
    body = b""
    for i in range(3):
        body += struct.pack(">dddf", i, i * i, 1.0, 0.5) + struct.pack(">Bf", 1, 2.0)
    body += struct.pack(">BIII", 3, 0, 1, 2) + struct.pack(">i", 7)
    files["binary_be.ply"] = header.encode() + body
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float32 x\n"
              "property float32 y\nproperty float32 z\nproperty uint32 rgb\n"
              "property float32 confidence\nproperty float32 curvature\n"
              "property int16 extra\nend_header\n")
    body = b"".join(struct.pack("<fffIffh", i, 0, 0, 0xff00ff, 0.9, 0.1, -3) for i in range(2))
    files["binary_le_packed.ply"] = header.encode() + body
    return files


def tiny_objs():
    return {
        "groups.obj": ("# groups, negative indices, normals and texture coordinates\n"
                       "mtllib none.mtl\no first\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                       "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\ng a b\nusemtl red\n"
                       "f 1/1/1 2/2/1 3/3/1\ng second\nf -4//1 -2//1 -1//1\ns off\n"
                       "l 1 2\np 3\n"),
        "colours.obj": "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 255\nf 1 2 3 \\\n\n",
        "polygon.obj": "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\nf 1 2 3 5 4\n",
    }


def other_meshes():
    return {
        "tetra.stl": ("solid t\nfacet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n"
                      "  vertex 0 1 0\n endloop\nendfacet\nfacet normal 0 0 1\n outer loop\n"
                      "  vertex 0 0 0\n  vertex 0 1 0\n  vertex 0 0 1\n endloop\nendfacet\n"
                      "endsolid t\n"),
        "tri.off": "OFF\n3 1 0\n0 0 0\n0.1 0 0\n0 0.1 0\n3 0 1 2\n",
        "tri.dae": (
            '<?xml version="1.0"?><COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" '
            'version="1.4.1"><library_geometries><geometry id="g"><mesh><source id="p">'
            '<float_array id="a" count="9">0 0 0 0.1 0 0 0 0.1 0</float_array>'
            '<technique_common><accessor source="#a" count="3" stride="3"><param name="X" '
            'type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>'
            '</accessor></technique_common></source><vertices id="v"><input semantic="POSITION" '
            'source="#p"/></vertices><triangles count="1"><input semantic="VERTEX" source="#v" '
            'offset="0"/><p>0 1 2</p></triangles></mesh></geometry></library_geometries>'
            '<library_visual_scenes><visual_scene id="s"><node name="part"><instance_geometry '
            'url="#g"/></node></visual_scene></library_visual_scenes><scene>'
            '<instance_visual_scene url="#s"/></scene></COLLADA>\n'),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cli", default=ROOT / "build" / "multicue")
    ap.add_argument("--data", default=ROOT.parent / "shared" / "data")
    ap.add_argument("--out", default=ROOT / "build-fuzz" / "seeds")
    args = ap.parse_args()
    cli, data, out = Path(args.cli), Path(args.data), Path(args.out)
    if not cli.is_file():
        sys.exit(f"fuzz_seeds.py: no CLI at {cli} (build the target multicue first)")
    if out.exists():
        shutil.rmtree(out)
    seeds = Seeds(out)
    tmp = Path(tempfile.mkdtemp(prefix="multicue-seeds-"))
    try:
        build_seeds(cli, data, tmp, seeds)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    for target, n in sorted(seeds.count.items()):
        print(f"{target:18s} {n:3d} seeds")


def build_seeds(cli, data, tmp, seeds):
    # Point clouds: PCD in all three encodings, PLY, from simulated scenes and the small scans.
    run(cli, "simulate", "scenes", "--scenes", "1", "--views", "2", "--objects", "3,3",
        "--out", tmp / "scenes", "-q")
    run(cli, "simulate", "objects", "--count", "6", "--views", "2", "--out", tmp / "objects", "-q")
    run(cli, "simulate", "scenes", "--scenes", "1", "--sensor", "laser", "--objects", "2,2",
        "--out", tmp / "laser", "-q")
    clouds = [tmp / "small.pcd"]
    run(cli, "downsample", tmp / "scenes" / "scene_0000_view_00.pcd", clouds[0], "--leaf", "0.12")
    for name in ["bunny.pcd", "bun0.pcd"]:
        if (data / "scans" / name).is_file():
            clouds.append(data / "scans" / name)
    laser = tmp / "laser_small.pcd"
    run(cli, "downsample", tmp / "laser" / "scene_0000_view_00.pcd", laser, "--leaf", "0.2")
    clouds.append(laser)
    run(cli, "normals", data / "scans" / "bunny.pcd" if (data / "scans" / "bunny.pcd").is_file()
        else clouds[0], tmp / "normals.pcd", "--k", "10")
    clouds.append(tmp / "normals.pcd")
    for cloud in clouds:
        for fmt in ["ascii", "binary", "compressed"]:
            p = tmp / f"{cloud.stem}_{fmt}.pcd"
            run(cli, "convert", cloud, p, "--format", fmt)
            seeds.add_file("pcd", p)
        for fmt in ["ascii", "binary"]:
            p = tmp / f"{cloud.stem}_{fmt}.ply"
            run(cli, "convert", cloud, p, "--format", fmt)
            seeds.add_file("ply", p)
    for name, text in tiny_pcds().items():
        seeds.add("pcd", name, text)
    for name, text in tiny_plys().items():
        seeds.add("ply", name, text)

    # Meshes: perceive's models.ply and triangulated scans, small shared meshes, hand-written OBJ.
    run(cli, "perceive", tmp / "scenes" / "scene_0000_view_00.pcd", "--out", tmp / "perceived",
        "--config", write(tmp / "rules.json", '{"category": {"categoriser": "rules"}}'),
        "--no-report", "-q")
    seeds.add_file("ply", tmp / "perceived" / "models.ply")
    seeds.add_file("perceive_config", tmp / "rules.json")
    run(cli, "mesh", clouds[-1], "--out", tmp / "bunny_mesh.ply")
    seeds.add_file("ply", tmp / "bunny_mesh.ply")
    for name, text in tiny_objs().items():
        seeds.add("obj", name, text)
    fmt_byte = {".obj": 0, ".ply": 1, ".stl": 2, ".off": 3, ".dae": 4, ".gltf": 5}
    for name, text in {**tiny_objs(), **other_meshes()}.items():
        seeds.add("mesh", name, bytes([fmt_byte[Path(name).suffix]]) + text.encode())
    seeds.add_file("mesh", tmp / "bunny_mesh.ply", "bunny_mesh.ply", bytes([1]))
    for suffix in [".obj", ".ply"]:
        meshes = sorted((p for folder in ["tabletop", "furniture"]
                         for p in (data / "meshes" / folder).glob("*" + suffix)),
                        key=lambda p: p.stat().st_size)
        for p in meshes[:3]:
            seeds.add_file(suffix[1:], p)
            seeds.add_file("mesh", p, prefix=bytes([fmt_byte[suffix]]))
    for folder in ["tabletop", "furniture", "kitchen"]:
        labels = data / "meshes" / folder / "labels.csv"
        if labels.is_file():
            lines = labels.read_text().splitlines()[:12]
            seeds.add("mesh_library", f"{folder}.csv", "\n".join(lines) + "\n")
    seeds.add("mesh_library", "self.csv",
              'file,category,scale_to_m,source,object\nlabels.csv,box,0.001,kit,"a, b"\n'
              "labels.csv,cylinder,,,\n")

    # Parameter files and task files.
    dump = subprocess.run([str(cli), "config", "--dump"], check=True, capture_output=True).stdout
    seeds.add("perceive_config", "dump.json", dump)
    seeds.add("perceive_config", "small.json",
              '{"support": {"up": [0, -1, 0]}, "clusters": {}, "report": {"enabled": false},\n'
              ' /* comment */ "num_threads": 2}\n')
    for name in ["objects", "scenes"]:
        manifest = (tmp / name / "manifest.json").read_bytes()
        seeds.add("sim_manifest", f"{name}.json", manifest)
        seeds.add("dataset_manifest", f"{name}.json", manifest)
        seeds.add("task", f"{name}_manifest.json", manifest)
    seeds.add("task", "sequence.yaml",
              "task: find\ntarget: tall mug\ndatabase: objects.db\nlearn: false\n"
              "region: {min: [-1, -1, 0.5], max: [1, 1, 2]}\npossible_objects: [tall mug, 3]\n"
              "params: perceive.json\noutput: run.json\nframes:\n"
              "  - {file: f0.pcd, time: 0, pose: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}\n"
              "  - f1.pcd\n  - 'quoted.pcd'\n")
    seeds.add("task", "manifest.yaml",
              "task: enumerate\nframes: {manifest: manifest.json, scenes: [0, 1]}\n"
              "anchors: &a [1, 2]\n")
    seeds.add("task", "task.json", json.dumps(
        {"task": "model", "target": "cylinder", "frames": ["a.pcd", {"file": "b.pcd"}]}))

    # Datasets, classifiers, transforms, ensembles from the simulated objects.
    mcd = tmp / "data.mcd"
    run(cli, "dataset", "extract", "--manifest", tmp / "objects" / "manifest.json", "-o", mcd,
        "--features", "grsd-minus,part-stats", "-q")
    seeds.add_payload("dataset", mcd)
    run(cli, "dataset", "convert", mcd, tmp / "data.csv")
    seeds.add_file("dataset_csv", tmp / "data.csv")
    seeds.add("dataset_csv", "quoted.csv",
              'row_id,group,view,label,source,a:x,"a:y,z",b\n1,2,3,"c/d",s,1.5,-2e3,0\n'
              '2,2,4,,"q""uote",0,0,1\n')
    for spec in ["knn:k=3,metric=hellinger", "knn:metric=l1", "svm:kernel=rbf",
                 "svm:kernel=linear", "boost:type=real,weak=5", "mlp:hidden=4", "rtrees:trees=3"]:
        model = tmp / (spec.split(":")[0] + spec.split("=")[-1] + ".mcm")
        run(cli, "classifier", "train", mcd, "-o", model, "--spec", spec)
        seeds.add_payload("classifier", model)
        seeds.add("classifier_spec", model.stem + ".txt", spec)
    for method in ["minmax", "zscore"]:
        t = tmp / f"{method}.mcx"
        run(cli, "dataset", "normalise", mcd, "-o", tmp / f"{method}.mcd", "--method", method,
            "--save", t)
        seeds.add_payload("transform", t)
    run(cli, "dataset", "pca", mcd, "-o", tmp / "pca.mcd", "--components", "3", "--save",
        tmp / "pca.mcx")
    seeds.add_payload("transform", tmp / "pca.mcx")
    run(cli, "dataset", "split", mcd, "-o", tmp / "half", "--method", "random",
        "--test-fraction", "0.5")
    run(cli, "ensemble", "train", tmp / "half_train.mcd", tmp / "half_test.mcd", "-o",
        tmp / "e.mce", "--member", "knn:k=1", "--level1", "knn:k=1")
    seeds.add_payload("ensemble", tmp / "e.mce")

    # Part-graph models of `multicue train` (small: one object per category, one view).
    for parts, stacker in [(1, 0), (2, 1)]:
        model = tmp / f"pg{parts}.mcpg"
        run(cli, "train", "--out", model, "--objects", "1", "--views", "1", "--max-parts", parts,
            "--table-scenes", "0", "--stacker-scenes", stacker, "--stacker-views", "1")
        seeds.add_payload("part_graph_model", model)

    # Object database: learnt by `multicue run` over the simulated scene, then exported.
    task = write(tmp / "learn.yaml", "task: enumerate\ndatabase: objects.db\nparams: rules.json\n"
                 "output: run.json\nframes: {manifest: scenes/manifest.json}\n")
    run(cli, "run", task)
    run(cli, "db", "export", tmp / "objects.db", "--out", tmp / "export.json")
    seeds.add_file("db_import", tmp / "export.json")
    seeds.add_file("db_file", tmp / "objects.db")
    run(cli, "db", "init", tmp / "empty.db")
    seeds.add_file("db_file", tmp / "empty.db")
    seeds.add("db_import", "tiny.json", json.dumps({
        "format": "multicue-object-database", "schema_version": 2, "objects": [{
            "name": "mug", "category": "cylinder", "created": 1, "last_seen": 2,
            "last_pose": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1],
            "views": [{"time": 2, "frame": "f.pcd", "category": "cylinder",
                       "category_probabilities": {"cylinder": 0.9}, "descriptors": {"vfh": [1, 2]},
                       "model": {"type": "cylinder"}, "mesh_ply_base64": "cGx5Cg==",
                       "pose": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}]}]}))
    for spec in ["knn", "svm:kernel=rbf,grid=1,c=10", "boost:type=gentle,weak=100,depth=2",
                 "mlp:hidden=32,iterations=10", "rtrees:trees=100,depth=3,scale=zscore",
                 "knn:k=5,metric=jm,seed=3,scale=none"]:
        seeds.add("classifier_spec", spec.replace(":", "_").replace(",", "_") + ".txt", spec)

    # URDF: the kitchen models' descriptions and a hand-written one with every joint type.
    urdfs = sorted((data / "meshes" / "kitchen").rglob("*.urdf"), key=lambda p: p.stat().st_size)
    for p in urdfs[:8]:
        seeds.add_file("urdf", p, f"{p.parent.parent.name}_{p.parent.name}.urdf")
    seeds.add("urdf", "joints.urdf", TINY_URDF)

    # Point cloud messages (CDR and ROS 1) and bags: the shared ROS 2 bags (strings and basic
    # types) and bags of point cloud messages written here.
    messages = [pointcloud2_message(*layout) for layout in MESSAGE_LAYOUTS]
    for i, m in enumerate(messages):
        seeds.add("point_cloud2", f"cdr_{i}", b"\x00" + encode_cdr(m))
        seeds.add("point_cloud2", f"ros1_{i}", b"\x01" + encode_ros1(m))
    for p in sorted((data / "bags" / "ros2").glob("*/*")):
        if p.suffix in (".db3", ".mcap"):
            seeds.add_file("ros2_bag", p, f"{p.parent.name}{p.suffix}",
                           bytes([1 if p.suffix == ".mcap" else 0]))
    db3 = tmp / "clouds.db3"
    write_db3(db3, [encode_cdr(m) for m in messages])
    seeds.add_file("ros2_bag", db3, prefix=b"\x00")
    bag = tmp / "clouds.bag"
    if write_ros1_bag(bag, [encode_ros1(m) for m in messages]):
        seeds.add_file("ros1_bag", bag)

    # A small furniture model: one procedural piece per class, two views, coarse CAD points.
    model = tmp / "furniture.mcfm"
    run(cli, "train", "furniture", "--out", model, "--meshes", "", "--kitchen", "",
        "--procedural", 1, "--views", 2, "--words", 8, "--cad-spacing", 0.15,
        "--verifier-rooms", 0, "-q")
    seeds.add_payload("furniture_model", model)


TINY_URDF = """<?xml version="1.0"?>
<robot name="cupboard">
  <material name="white"><color rgba="1 1 1 1"/></material>
  <link name="body"><visual><origin xyz="0 0 0.4" rpy="0 0 0"/>
    <geometry><box size="0.6 0.5 0.8"/></geometry><material name="white"/></visual></link>
  <link name="door"><visual><geometry><mesh filename="door.obj" scale="0.001 0.001 0.001"/>
    </geometry></visual></link>
  <link name="drawer"/><link name="handle"/>
  <joint name="door_hinge" type="revolute"><parent link="body"/><child link="door"/>
    <origin xyz="0.3 -0.25 0.4" rpy="0 0 1.5708"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="1.57" effort="1" velocity="1"/></joint>
  <joint name="drawer_slide" type="prismatic"><parent link="body"/><child link="drawer"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.4" effort="1" velocity="1"/></joint>
  <joint name="handle_fixed" type="fixed"><parent link="drawer"/><child link="handle"/></joint>
</robot>
"""

# (height, width, fields as (name, offset, datatype, count), point_step, big endian)
MESSAGE_LAYOUTS = [
    (1, 3, [("x", 0, 7, 1), ("y", 4, 7, 1), ("z", 8, 7, 1), ("rgb", 16, 7, 1)], 32, False),
    (2, 2, [("x", 0, 7, 1), ("y", 4, 7, 1), ("z", 8, 7, 1), ("intensity", 12, 7, 1)], 16, False),
    (1, 2, [("z", 8, 7, 1), ("x", 0, 7, 1), ("y", 4, 7, 1), ("normal_x", 12, 7, 1),
            ("normal_y", 16, 7, 1), ("normal_z", 20, 7, 1), ("label", 24, 6, 1),
            ("r", 28, 2, 1), ("g", 29, 2, 1), ("b", 30, 2, 1), ("ring", 31, 1, 1)], 32, True),
    (1, 2, [("x", 0, 8, 1), ("y", 8, 8, 1), ("z", 16, 8, 1), ("t", 24, 4, 1)], 28, False),
]


def pointcloud2_message(height, width, fields, point_step, big_endian):
    order = ">" if big_endian else "<"
    fmt = {1: "b", 2: "B", 3: "h", 4: "H", 5: "i", 6: "I", 7: "f", 8: "d"}
    data = bytearray(point_step * width * height)
    for i in range(width * height):
        for name, offset, datatype, _ in fields:
            value = {"x": 0.1 * i, "y": -0.05 * i, "z": 1.0 + 0.01 * i}.get(name, i % 7)
            if datatype not in (7, 8):
                value = int(value)
            struct.pack_into(order + fmt[datatype], data, i * point_step + offset, value)
    return {"stamp": (12, 345), "frame_id": "camera", "height": height, "width": width,
            "fields": fields, "big_endian": big_endian, "point_step": point_step,
            "row_step": point_step * width, "data": bytes(data), "dense": True}


def encode_cdr(m):
    """CDR (little endian) with its encapsulation header, as rosbag2 stores it."""
    out = bytearray()

    def align(n):
        out.extend(b"\0" * (-len(out) % n))

    def u32(v):
        align(4)
        out.extend(struct.pack("<I", v))

    def string(s):
        u32(len(s) + 1)
        out.extend(s.encode() + b"\0")

    out.extend(struct.pack("<iI", *m["stamp"]))
    string(m["frame_id"])
    u32(m["height"])
    u32(m["width"])
    u32(len(m["fields"]))
    for name, offset, datatype, count in m["fields"]:
        string(name)
        u32(offset)
        out.append(datatype)
        u32(count)
    out.append(1 if m["big_endian"] else 0)
    u32(m["point_step"])
    u32(m["row_step"])
    u32(len(m["data"]))
    out.extend(m["data"])
    out.append(1 if m["dense"] else 0)
    return b"\x00\x01\x00\x00" + bytes(out)


def encode_ros1(m):
    """ROS 1 serialisation: little endian, no alignment, strings without their NUL."""
    def string(s):
        return struct.pack("<I", len(s)) + s.encode()

    out = struct.pack("<III", 0, *m["stamp"]) + string(m["frame_id"])
    out += struct.pack("<III", m["height"], m["width"], len(m["fields"]))
    for name, offset, datatype, count in m["fields"]:
        out += string(name) + struct.pack("<IBI", offset, datatype, count)
    out += struct.pack("<BII", 1 if m["big_endian"] else 0, m["point_step"], m["row_step"])
    out += struct.pack("<I", len(m["data"])) + m["data"] + bytes([1 if m["dense"] else 0])
    return out


def write_db3(path, messages):
    """A rosbag2 SQLite bag (schema version 4) of point cloud messages."""
    import sqlite3
    db = sqlite3.connect(path)
    db.executescript(
        "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);"
        "INSERT INTO schema VALUES(4, 'humble');"
        "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,"
        " serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL,"
        " type_description_hash TEXT NOT NULL);"
        "INSERT INTO topics VALUES(1, '/points', 'sensor_msgs/msg/PointCloud2', 'cdr', '', '');"
        "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,"
        " timestamp INTEGER NOT NULL, data BLOB NOT NULL);")
    db.executemany("INSERT INTO messages(topic_id, timestamp, data) VALUES(1, ?, ?)",
                   [(1000 * (i + 1), m) for i, m in enumerate(messages)])
    db.commit()
    db.close()


ROS1_BAG_WRITER = """
import sys, rosbag, rospy
class PointCloud2:
    _type = "sensor_msgs/PointCloud2"
    _md5sum = "1158d486dd51d683ce2f1be655c3c181"
    _full_text = "Header header\\nuint32 height\\nuint32 width\\nPointField[] fields\\n"
with rosbag.Bag(sys.argv[1], "w") as bag:
    for i, path in enumerate(sys.argv[2:]):
        data = open(path, "rb").read()
        bag.write("/points", (PointCloud2._type, data, PointCloud2._md5sum, None, PointCloud2),
                  rospy.Time(1, 1000 * i), raw=True)
"""


def write_ros1_bag(path, messages):
    """A ROS 1 bag through Debian's Python rosbag (python3-rosbag); False when it is missing."""
    python = Path("/usr/bin/python3")
    if not python.is_file():
        return False
    files = []
    for i, m in enumerate(messages):
        files.append(path.with_name(f"message_{i}.bin"))
        files[-1].write_bytes(m)
    result = subprocess.run([str(python), "-c", ROS1_BAG_WRITER, str(path), *map(str, files)],
                            capture_output=True)
    return result.returncode == 0 and path.is_file()


def write(path, text):
    Path(path).write_text(text)
    return path


if __name__ == "__main__":
    main()
