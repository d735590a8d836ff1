"""`granplate bench`: speed and accuracy of the schemes on the presets."""


def write_report(args, report) -> None:
    """With --json FILE (args.json), the report as indented JSON to FILE, and a line naming it."""
    path = getattr(args, "json", None)
    if not path:
        return
    import json

    with open(path, "w") as fh:
        fh.write(json.dumps(report, indent=2) + "\n")
    print(f"json: {path}")
