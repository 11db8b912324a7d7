"""What the benchmark drivers share (run.py and holes.py import it; neither
imports the other for it): the machine line of every section, and meshes
written as OFF files with every coordinate exact."""
import os
import platform


def machine():
    """'2 cores (CPU model), Linux 6.x': the line each section starts with."""
    cpu = "?"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{os.cpu_count()} cores ({cpu}), {platform.system()} {platform.release()}"


def write_off(path, points, faces):
    """An OFF file, each coordinate written exactly (shortest round-trip
    repr); `points` and `faces` as lists or NumPy arrays. Returns the path."""
    points = points.tolist() if hasattr(points, "tolist") else points
    faces = faces.tolist() if hasattr(faces, "tolist") else faces
    with open(path, "w") as f:
        f.write(f"OFF\n{len(points)} {len(faces)} 0\n")
        f.writelines(f"{float(x)!r} {float(y)!r} {float(z)!r}\n" for x, y, z in points)
        f.writelines(f"{len(t)} " + " ".join(str(int(i)) for i in t) + "\n" for t in faces)
    return path
