"""scene_json.py — a scene in the 2025 JSON form as the XML element tree it stands for, by the rule clrt's
reader follows (src/scene/json_node.cpp, docs/scene-format.md "The JSON form"): {"Scene": {...}} is the root;
a key starting with '_' is an attribute, "_data" an element's text when it also has attributes; an array of
objects or strings repeats its element, any other array is one element whose text is its values
space-separated; a value's text is as clrt writes it (true/false, integers, floats in JSON's shortest form).
Used by scripts/check_course.py and bench/bench_mitsuba_path.py. Standard library only."""
import json
import xml.etree.ElementTree as ET


def scalar_text(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, list):
        return " ".join(scalar_text(x) for x in v)
    if isinstance(v, float):
        return json.dumps(v)
    if isinstance(v, (dict, type(None))):
        return ""
    return str(v)


def json_to_element(tag, value):
    """The element `tag` whose JSON value is `value`, with its attributes, text and children."""
    e = ET.Element(tag)
    if not isinstance(value, dict):
        e.text = scalar_text(value)
        return e
    for k, v in value.items():
        if not k:
            continue
        if k == "_data":
            e.text = scalar_text(v)
        elif k.startswith("_"):
            e.set(k[1:], scalar_text(v))
        elif isinstance(v, list) and v and isinstance(v[0], (dict, str)):
            for item in v:
                e.append(json_to_element(k, item))
        else:
            e.append(json_to_element(k, v))
    return e
