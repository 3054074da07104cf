"""Reads a USD mesh sequence with Pixar's library and prints what a DCC tool would see, as JSON:
stage metadata, the mesh's faces, points and displayColor at every time code, the tracks, and
what every registered UsdValidation validator reports (usdchecker's checks since USD 25.02). The tests compare it with what tagsplat wrote."""
import json
import sys

from pxr import Usd, UsdGeom, UsdValidation


def at_every_time(attribute, stage):
    start, end = int(stage.GetStartTimeCode()), int(stage.GetEndTimeCode())
    return [[list(v) for v in attribute.Get(Usd.TimeCode(t))] for t in range(start, end + 1)]


def main(path):
    stage = Usd.Stage.Open(path)
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Sequence/Mesh"))
    report = {
        "up_axis": UsdGeom.GetStageUpAxis(stage),
        "time_codes_per_second": stage.GetTimeCodesPerSecond(),
        "start": stage.GetStartTimeCode(),
        "end": stage.GetEndTimeCode(),
        "default_prim": str(stage.GetDefaultPrim().GetPath()),
        "face_vertex_counts": list(mesh.GetFaceVertexCountsAttr().Get()),
        "face_vertex_indices": list(mesh.GetFaceVertexIndicesAttr().Get()),
        "points": at_every_time(mesh.GetPointsAttr(), stage),
    }
    color = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("displayColor")
    if color:
        report["color_interpolation"] = color.GetInterpolation()
        report["colors"] = at_every_time(color.GetAttr(), stage)
    tracks = stage.GetPrimAtPath("/Sequence/Tracks")
    if tracks:
        points = UsdGeom.Points(tracks)
        report["tracks"] = at_every_time(points.GetPointsAttr(), stage)
        report["track_ids"] = list(UsdGeom.PrimvarsAPI(points).GetPrimvar("trackIds").Get())
    validators = UsdValidation.ValidationRegistry().GetOrLoadAllValidators()
    findings = UsdValidation.ValidationContext(validators).Validate(stage)
    describe = lambda f: f"{f.GetName()}: {f.GetMessage()}"
    error = UsdValidation.ValidationErrorType.Error
    report["validators"] = len(validators)
    report["errors"] = [describe(f) for f in findings if f.GetType() == error]
    report["warnings"] = [describe(f) for f in findings if f.GetType() != error]
    print(json.dumps(report))


if __name__ == "__main__":
    main(sys.argv[1])
