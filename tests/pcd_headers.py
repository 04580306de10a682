"""Hand-built PCD headers for the PCD reader's tests."""


def pcd_header(fields, sizes, types, width, height=1, data="binary", counts=None) -> bytes:
    counts = counts or [1] * len(fields)
    lines = [
        "# .PCD v0.7 - Point Cloud Data file format",
        "VERSION 0.7",
        "FIELDS " + " ".join(fields),
        "SIZE " + " ".join(map(str, sizes)),
        "TYPE " + " ".join(types),
        "COUNT " + " ".join(map(str, counts)),
        f"WIDTH {width}",
        f"HEIGHT {height}",
        "VIEWPOINT 0 0 0 1 0 0 0",
        f"POINTS {width * height}",
        f"DATA {data}",
    ]
    return ("\n".join(lines) + "\n").encode()
