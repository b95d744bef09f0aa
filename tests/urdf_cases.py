"""A table of URDF edge cases (about 190), built in memory.

Written for the urdfdom survey behind docs/api.md ("URDF rules"): every quirk
of urdfdom 3.0.1 that a mirror parser has to reproduce, plus inputs that crash
urdfdom itself (format strings in <origin>, deep nesting, huge chains).
"""

from __future__ import annotations

LIM = '<limit lower="-1" upper="1" effort="10" velocity="2"/>'

def robot(body, name='r', extra=''):
    n = '' if name is None else f' name="{name}"'
    return f'<?xml version="1.0"?>\n<robot{n}{extra}>\n{body}\n</robot>\n'

def links(*names):
    return "\n".join(f'  <link name="{n}"/>' for n in names)

def joint(name, typ, parent, child, inner='', typeattr=True):
    t = f' type="{typ}"' if typeattr else ''
    p = f'<parent link="{parent}"/>' if parent is not None else ''
    c = f'<child link="{child}"/>' if child is not None else ''
    return f'  <joint name="{name}"{t}>{p}{c}{inner}</joint>'

def chain1(inner, typ="revolute"):
    """base -> l1 via joint j1 with given inner xml"""
    return robot(links("base", "l1") + "\n" + joint("j1", typ, "base", "l1", inner))

cases = []
def add(name, text, desc=None):
    cases.append((name, text, desc or name))

# --- baseline
add("baseline_2joint", robot(links("base", "l1", "l2") + "\n" +
    joint("j1", "revolute", "base", "l1", '<origin xyz="0 0 0.5" rpy="0 0 1.5707963267948966"/><axis xyz="0 0 1"/>' + LIM) + "\n" +
    joint("j2", "prismatic", "l1", "l2", '<origin xyz="1 0 0"/><axis xyz="1 0 0"/><limit lower="0" upper="0.5" effort="5" velocity="1"/>')))
# --- document-level
add("empty_string", "")
add("whitespace_only", "   \n  ")
add("not_xml", "this is not xml at all")
add("truncated_xml", '<robot name="r"><link name="a"/>')
add("mismatched_tags", '<robot name="r"><link name="a"></joint></robot>')
add("xml_without_robot", '<?xml version="1.0"?>\n<model name="r"><link name="a"/></model>\n')
add("robot_not_first_element", '<?xml version="1.0"?>\n<foo/>\n<robot name="r"><link name="a"/></robot>\n')
add("two_robot_elements", '<robot name="r1"><link name="a"/></robot><robot name="r2"><link name="b"/></robot>')
add("robot_without_name", robot(links("a"), name=None))
add("robot_empty_name", robot(links("a"), name=""))
add("robot_version_1.0", robot(links("a"), extra=' version="1.0"'))
add("robot_version_2.0", robot(links("a"), extra=' version="2.0"'))
add("robot_version_1", robot(links("a"), extra=' version="1"'))
add("robot_version_1.0.0", robot(links("a"), extra=' version="1.0.0"'))
add("robot_version_1.x", robot(links("a"), extra=' version="1.x"'))
add("robot_version_1..0", robot(links("a"), extra=' version="1..0"'))
add("robot_version_.1.0", robot(links("a"), extra=' version=".1.0"'))
add("robot_version_1.0..", robot(links("a"), extra=' version="1.0.."'))
add("robot_version_1.0.", robot(links("a"), extra=' version="1.0."'))
add("robot_version_.1", robot(links("a"), extra=' version=".1"'))
add("robot_version_empty", robot(links("a"), extra=' version=""'))
add("robot_no_links", robot(""))
add("robot_one_link_no_joints", robot(links("only")))
add("links_namespaced_in_other_elem", robot('<gazebo><link name="g"/></gazebo>' + links("a")))
# --- links
add("link_without_name", robot('<link/>' + links("a")))
add("link_empty_name", robot('<link name=""/>'))
add("duplicate_link_names", robot(links("a", "a")))
add("link_unicode_name", robot(links("bäse_链接", "l1") + "\n" + joint("jø", "fixed", "bäse_链接", "l1")))
add("link_name_with_spaces", robot(links(" a ", "b") + "\n" + joint("j", "fixed", " a ", "b")))
add("link_name_entity_amp", robot('<link name="a&amp;b"/><link name="c"/>' + joint("j", "fixed", "a&amp;b", "c")))
add("link_bad_inertial_mass", robot('<link name="a"><inertial><mass value="abc"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>'))
add("link_inertial_no_mass", robot('<link name="a"/><link name="b"><inertial><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>' + joint("j","fixed","a","b")))
add("root_link_with_inertia", robot('<link name="a"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link><link name="b"/>' + joint("j","fixed","a","b")))
add("visual_undefined_material", robot('<link name="a"><visual><geometry><box size="1 1 1"/></geometry><material name="nope"/></visual></link>'))
# --- joint topology
add("duplicate_joint_names", robot(links("a", "b", "c") + joint("j", "fixed", "a", "b") + joint("j", "fixed", "b", "c")))
add("joint_without_name", robot(links("a", "b") + '<joint type="fixed"><parent link="a"/><child link="b"/></joint>'))
add("joint_missing_parent_elem", robot(links("a", "b") + joint("j", "fixed", None, "b")))
add("joint_missing_child_elem", robot(links("a", "b") + joint("j", "fixed", "a", None)))
add("joint_parent_no_link_attr", robot(links("a", "b") + '<joint name="j" type="fixed"><parent/><child link="b"/></joint>'))
add("joint_parent_empty_link_attr", robot(links("a", "b") + joint("j", "fixed", "", "b")))
add("joint_parent_link_nonexistent", robot(links("a", "b") + joint("j", "fixed", "zzz", "b")))
add("joint_child_link_nonexistent", robot(links("a", "b") + joint("j", "fixed", "a", "zzz")))
add("joint_both_links_nonexistent", robot(links("a") + joint("j", "fixed", "p", "c")))
add("two_root_links_disconnected", robot(links("a", "b", "c") + joint("j", "fixed", "a", "b")))
add("two_root_links_no_joints", robot(links("b", "a")))
add("cycle_two_links", robot(links("a", "b") + joint("j1", "fixed", "a", "b") + joint("j2", "fixed", "b", "a")))
add("cycle_with_root", robot(links("r", "a", "b") + joint("j0", "fixed", "r", "a") + joint("j1", "fixed", "a", "b") + joint("j2", "fixed", "b", "a")))
add("link_with_two_parents", robot(links("a", "b", "c") + joint("j1", "fixed", "a", "c") + joint("j2", "fixed", "b", "c")))
add("link_with_two_parents_same_parent", robot(links("a", "c") + joint("j1", "fixed", "a", "c") + joint("j2", "fixed", "a", "c")))
add("self_loop_joint", robot(links("a") + joint("j", "fixed", "a", "a")))
add("joint_order_child_first", robot(links("l2", "l1", "base") + joint("jb", "fixed", "l1", "l2") + joint("ja", "fixed", "base", "l1")))
# --- joint type
add("joint_type_missing", robot(links("a", "b") + joint("j", None, "a", "b", typeattr=False)))
add("joint_type_bogus", robot(links("a", "b") + joint("j", "bogus", "a", "b")))
add("joint_type_uppercase", robot(links("a", "b") + joint("j", "Revolute", "a", "b", LIM)))
add("joint_type_empty", robot(links("a", "b") + joint("j", "", "a", "b")))
add("joint_type_unknown_str", robot(links("a", "b") + joint("j", "unknown", "a", "b")))
add("floating_joint", chain1('<origin xyz="1 2 3"/><axis xyz="0 0 5"/>', "floating"))
add("planar_joint", chain1('<origin xyz="1 2 3"/><axis xyz="0 0 5"/>', "planar"))
add("planar_joint_no_axis", chain1('', "planar"))
add("fixed_joint_with_axis_garbage", chain1('<axis xyz="a b c"/>', "fixed"))
add("floating_with_limit", chain1('<limit effort="1" velocity="1"/>', "floating"))
# --- limits
add("revolute_without_limit", chain1('<axis xyz="0 0 1"/>', "revolute"))
add("prismatic_without_limit", chain1('<axis xyz="0 0 1"/>', "prismatic"))
add("continuous_without_limit", chain1('<axis xyz="0 0 1"/>', "continuous"))
add("continuous_with_limit", chain1('<axis xyz="0 0 1"/>' + LIM, "continuous"))
add("fixed_with_limit", chain1(LIM, "fixed"))
add("limit_missing_lower", chain1('<limit upper="1" effort="10" velocity="2"/>'))
add("limit_missing_upper", chain1('<limit lower="-1" effort="10" velocity="2"/>'))
add("limit_missing_effort", chain1('<limit lower="-1" upper="1" velocity="2"/>'))
add("limit_missing_velocity", chain1('<limit lower="-1" upper="1" effort="10"/>'))
add("limit_empty_element", chain1('<limit/>'))
add("limit_lower_gt_upper", chain1('<limit lower="2" upper="1" effort="10" velocity="2"/>'))
add("limit_velocity_neg1", chain1('<limit lower="-1" upper="1" effort="10" velocity="-1"/>'))
add("limit_velocity_0", chain1('<limit lower="-1" upper="1" effort="10" velocity="0"/>'))
add("limit_effort_neg", chain1('<limit lower="-1" upper="1" effort="-5" velocity="1"/>'))
add("limit_upper_1.5708abc", chain1('<limit lower="-1" upper="1.5708abc" effort="10" velocity="2"/>'))
add("limit_effort_1.5708abc", chain1('<limit lower="-1" upper="1" effort="1.5708abc" velocity="2"/>'))
add("limit_lower_empty_str", chain1('<limit lower="" upper="1" effort="10" velocity="2"/>'))
add("limit_upper_spaces", chain1('<limit lower="-1" upper=" 1 " effort="10" velocity="2"/>'))
add("limit_upper_leading_space", chain1('<limit lower="-1" upper=" 1" effort="10" velocity="2"/>'))
add("limit_upper_nan", chain1('<limit lower="-1" upper="nan" effort="10" velocity="2"/>'))
add("limit_upper_inf", chain1('<limit lower="-1" upper="inf" effort="10" velocity="2"/>'))
add("limit_upper_1e400", chain1('<limit lower="-1" upper="1e400" effort="10" velocity="2"/>'))
add("limit_upper_1e-400", chain1('<limit lower="-1" upper="1e-400" effort="10" velocity="2"/>'))
add("limit_upper_two_numbers", chain1('<limit lower="-1" upper="1 2" effort="10" velocity="2"/>'))
add("two_limit_elements", chain1('<limit lower="-1" upper="1" effort="10" velocity="2"/><limit lower="-5" upper="5" effort="10"/>'))
# --- axis
add("revolute_missing_axis", chain1(LIM))
add("prismatic_missing_axis", chain1(LIM, "prismatic"))
add("axis_without_xyz_attr", chain1('<axis/>' + LIM))
add("axis_0_0_0", chain1('<axis xyz="0 0 0"/>' + LIM))
add("axis_0_0_2", chain1('<axis xyz="0 0 2"/>' + LIM))
add("axis_1_1_0", chain1('<origin rpy="0 0 1.5707963267948966"/><axis xyz="1 1 0"/>' + LIM))
add("axis_prismatic_0_0_2", chain1('<axis xyz="0 0 2"/>' + LIM, "prismatic"))
add("axis_2_components", chain1('<axis xyz="0 1"/>' + LIM))
add("axis_4_components", chain1('<axis xyz="0 0 1 0"/>' + LIM))
add("axis_empty_string", chain1('<axis xyz=""/>' + LIM))
add("axis_non_numeric", chain1('<axis xyz="0 z 1"/>' + LIM))
add("axis_0_0_1e-300", chain1('<axis xyz="0 0 1e-300"/>' + LIM))
# --- origin
add("missing_origin", chain1('<axis xyz="0 0 1"/>' + LIM))
add("origin_empty_element", chain1('<origin/>' + LIM))
add("origin_only_rpy", chain1('<origin rpy="0 0 3.141592653589793"/>' + LIM))
add("origin_only_xyz", chain1('<origin xyz="1 2 3"/>' + LIM))
def xyz(v: str) -> str:
    return chain1(f'<origin xyz="{v}"/>' + LIM)
add("xyz_1_abc_0", xyz("1 abc 0"))
add("xyz_nan", xyz("nan 0 0"))
add("xyz_NaN", xyz("NaN 0 0"))
add("xyz_inf", xyz("inf 0 0"))
add("xyz_-inf", xyz("-inf 0 0"))
add("xyz_1e400", xyz("1e400 0 0"))
add("xyz_1e-400", xyz("1e-400 0 0"))
add("xyz_hex_0x10", xyz("0x10 0 0"))
add("xyz_comma_decimal_1,5", xyz("1,5 0 0"))
add("xyz_comma_separated", xyz("1,0,0"))
add("xyz_leading_trailing_spaces", xyz("  1   2  3  "))
add("xyz_tab_separated", xyz("1\t2\t3"))
add("xyz_newline_separated", xyz("1\n2\n3"))
add("xyz_tab_entity_separated", xyz("1&#9;2&#9;3"))
add("xyz_plus_1", xyz("+1 0 0"))
add("xyz_dot5", xyz(".5 0 0"))
add("xyz_5dot", xyz("5. 0 0"))
add("xyz_1e2", xyz("1e2 0 0"))
add("xyz_1E+2", xyz("1E+2 0 0"))
add("xyz_minus_zero", xyz("-0 0 0"))
add("xyz_2_components", xyz("1 2"))
add("xyz_4_components", xyz("1 2 3 4"))
add("xyz_empty_string", xyz(""))
add("xyz_only_spaces", xyz("   "))
add("xyz_printf_format", xyz("1 %s%s%s%s 0"))
add("xyz_very_long_junk", xyz("1 " + "x" * 1500 + " 0"))
add("rpy_2_components", chain1('<origin rpy="0 1"/>' + LIM))
add("rpy_non_numeric", chain1('<origin rpy="0 a 1"/>' + LIM))
add("rpy_nan", chain1('<origin rpy="nan 0 0"/>' + LIM))
add("rpy_large_angles", chain1('<origin rpy="7 0 -7"/>' + LIM))
add("rpy_gimbal_pitch_pi2", chain1('<origin rpy="0.3 1.5707963267948966 0.2"/>' + LIM))
add("two_origin_elements", chain1('<origin xyz="1 0 0"/><origin xyz="2 0 0"/>' + LIM))
# --- mimic
base3 = links("base", "l1", "l2")
base4 = links("base", "l1", "l2", "l3")
add("mimic_full", robot(base3 + joint("j1", "revolute", "base", "l1", LIM) + joint("j2", "revolute", "l1", "l2", LIM + '<mimic joint="j1" multiplier="2" offset="0.5"/>')))
add("mimic_defaults", robot(base3 + joint("j1", "revolute", "base", "l1", LIM) + joint("j2", "revolute", "l1", "l2", LIM + '<mimic joint="j1"/>')))
add("mimic_unknown_joint", robot(base3 + joint("j1", "revolute", "base", "l1", LIM) + joint("j2", "revolute", "l1", "l2", LIM + '<mimic joint="nope"/>')))
add("mimic_no_joint_attr", robot(base3 + joint("j1", "revolute", "base", "l1", LIM) + joint("j2", "revolute", "l1", "l2", LIM + '<mimic multiplier="2"/>')))
add("mimic_of_mimic", robot(base4 + joint("j1", "revolute", "base", "l1", LIM) + joint("j2", "revolute", "l1", "l2", LIM + '<mimic joint="j1" multiplier="2"/>') + joint("j3", "revolute", "l2", "l3", LIM + '<mimic joint="j2" multiplier="3" offset="1"/>')))
add("mimic_self", robot(links("base", "l1") + joint("j1", "revolute", "base", "l1", LIM + '<mimic joint="j1"/>')))
add("mimic_bad_multiplier", robot(base3 + joint("j1", "revolute", "base", "l1", LIM) + joint("j2", "revolute", "l1", "l2", LIM + '<mimic joint="j1" multiplier="two"/>')))
add("mimic_on_fixed_joint", robot(base3 + joint("j1", "revolute", "base", "l1", LIM) + joint("j2", "fixed", "l1", "l2", '<mimic joint="j1" multiplier="2"/>')))
# --- other joint children
add("joint_unknown_child_elements", chain1('<foo bar="1"/><axis xyz="0 0 1"/>' + LIM + '<whatever><nested/></whatever>'))
add("joint_unknown_attributes", robot(links("a","b") + '<joint name="j" type="fixed" foo="bar"><parent link="a" extra="1"/><child link="b"/></joint>'))
add("dynamics_empty", chain1(LIM + '<dynamics/>'))
add("dynamics_damping_only", chain1(LIM + '<dynamics damping="0.5"/>'))
add("safety_no_k_velocity", chain1(LIM + '<safety_controller soft_lower_limit="0"/>'))
add("calibration_bad", chain1(LIM + '<calibration rising="x"/>'))
# --- XML features
add("billion_laughs", '''<?xml version="1.0"?>
<!DOCTYPE lolz [
 <!ENTITY lol "lol">
 <!ENTITY lol1 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
 <!ENTITY lol2 "&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;">
 <!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">
 <!ENTITY lol9 "&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;">
]>
<robot name="&lol9;"><link name="&lol9;"/></robot>
''')
add("doctype_internal_entity_used", '''<?xml version="1.0"?>
<!DOCTYPE robot [ <!ENTITY nm "base"> ]>
<robot name="r"><link name="&nm;"/></robot>
''')
add("doctype_simple_no_subset", '''<?xml version="1.0"?>
<!DOCTYPE robot>
<robot name="r"><link name="a"/></robot>
''')
add("external_entity_SYSTEM", '''<?xml version="1.0"?>
<!DOCTYPE robot [ <!ENTITY xxe SYSTEM "file:///etc/hostname"> ]>
<robot name="r"><link name="&xxe;"/></robot>
''')
# names starting with ':' are XML names; urdfdom's TinyXML refuses them as attribute names
# (found by tests/fuzz_urdf_loader.py under ASan) but reads them as element names
add("attribute_name_starting_with_colon", chain1('<limit lower="-1" :pper="1" effort="10" velocity="2"/>'))
add("root_attribute_name_starting_with_colon", robot(links("base"), extra=' :v="1"'))
add("element_name_starting_with_colon", robot(links("base") + "<:x/>"))
add("attribute_name_with_inner_colon", robot(links("base") + '<x a:b="1"/>'))
add("predefined_and_numeric_entities", robot('<link name="a&lt;&#65;&#x42;&gt;"/>'))
add("unknown_entity_in_attr", robot('<link name="a&foo;b"/>'))
add("xml_comment_and_pi", '<?xml version="1.0"?><!-- c --><?pi x?><robot name="r"><!-- c2 --><link name="a"/></robot>')
add("cdata_in_robot", robot('<![CDATA[ junk ]]>' + links("a")))
add("bom_utf8", "\ufeff" + robot(links("a")))
add("utf16_decl_ascii_body", '<?xml version="1.0" encoding="UTF-16"?><robot name="r"><link name="a"/></robot>')
add("trailing_garbage_after_root", robot(links("a")) + "garbage text")
add("trailing_element_after_root", robot(links("a")) + "<extra/>")
add("namespace_prefixed_robot", '<u:robot xmlns:u="http://x" name="r"><u:link name="a"/></u:robot>')
add("robot_with_xmlns", '<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="r"><link name="a"/></robot>')
add("duplicate_attribute", '<robot name="r" name="s"><link name="a"/></robot>')
add("unquoted_attr", '<robot name=r><link name="a"/></robot>')
add("single_quoted_attrs", "<robot name='r'><link name='a'/></robot>")

# --- additional cases (round 2)
add("mimic_cycle_j1_j2", robot(base3 + joint("j1", "revolute", "base", "l1", LIM + '<mimic joint="j2"/>') + joint("j2", "revolute", "l1", "l2", LIM + '<mimic joint="j1"/>')))
add("mimic_empty_joint_attr", robot(base3 + joint("j1", "revolute", "base", "l1", LIM) + joint("j2", "revolute", "l1", "l2", LIM + '<mimic joint=""/>')))
add("mimic_on_continuous_neg_mult", robot(base3 + joint("j1", "continuous", "base", "l1", '') + joint("j2", "continuous", "l1", "l2", '<mimic joint="j1" multiplier="-1" offset="-0.25"/>')))
add("diamond_two_parents_single_root", robot(links("r", "a", "b", "c") + joint("j0", "fixed", "r", "a") + joint("j1", "fixed", "r", "b") + joint("j2", "fixed", "a", "c") + joint("j3", "fixed", "b", "c")))
add("leading_text_before_robot", 'hello <robot name="r"><link name="a"/></robot>')
add("element_then_text_then_robot", '<a/> hello <robot name="r"><link name="a"/></robot>')
add("doctype_empty_internal_subset", '<?xml version="1.0"?>\n<!DOCTYPE robot [ ]>\n<robot name="r"><link name="a"/></robot>\n')
add("bare_ampersand_in_attr", robot('<link name="a & b"/>'))
add("lt_in_attr", robot('<link name="a<b"/>'))
add("xyz_printf_percent_n", xyz("1 %n%n%n%n 0"))
add("xyz_printf_many_s", xyz("1 " + "%s" * 40 + " 0"))
add("xyz_denormal_1e-310", xyz("1e-310 0 0"))
add("xyz_1e308", xyz("1e308 0 0"))
add("xyz_infinity_word", xyz("infinity 0 0"))
add("xyz_double_spaces", xyz("1  2   3"))
add("xyz_nbsp_separated", xyz("1\u00a02 3"))
add("joint_empty_name", robot(links("a", "b") + joint("", "fixed", "a", "b")))
add("link_no_name_single", robot('<link/>'))
add("link_bad_visual_geometry", robot('<link name="a"><visual><geometry><box size="1 1"/></geometry></visual><collision><geometry><sphere radius="1"/></geometry></collision></link>'))
add("material_not_unique", robot('<material name="m"><color rgba="1 0 0 1"/></material><material name="m"><color rgba="0 1 0 1"/></material>' + links("a")))
add("material_no_color_no_texture", robot('<material name="m"/>' + links("a")))
add("robot_name_unicode", robot(links("a"), name="робот"))
add("limit_on_continuous_missing_effort", chain1('<limit lower="0" upper="1" velocity="1"/>', "continuous"))
add("limit_lower_nan_on_fixed", chain1('<limit lower="nan" effort="1" velocity="1"/>', "fixed"))
add("origin_on_fixed_rpy_and_xyz", chain1('<origin xyz="0.1 0.2 0.3" rpy="0.1 0.2 0.3"/>', "fixed"))
add("axis_negative_z_continuous", chain1('<origin rpy="1.5707963267948966 0 0"/><axis xyz="0 0 -3"/>', "continuous"))
add("joint_children_reordered", robot(links("a", "b") + '<joint name="j" type="revolute"><limit effort="1" velocity="1"/><axis xyz="0 1 0"/><child link="b"/><origin xyz="1 0 0"/><parent link="a"/></joint>'))
add("two_parent_elements", robot(links("a", "b", "c") + '<joint name="j" type="fixed"><parent link="a"/><parent link="c"/><child link="b"/></joint>' + joint("k","fixed","b","c")))

# --- big
N = 2000
body = "\n".join(f'  <link name="l{i}"/>' for i in range(N + 1)) + "\n" + "\n".join(
    f'  <joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i+1}"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>{LIM}</joint>' for i in range(N))
add("big_chain_2000", robot(body))
N = 20000
body = "\n".join(f'  <link name="l{i}"/>' for i in range(N + 1)) + "\n" + "\n".join(
    f'  <joint name="j{i}" type="fixed"><parent link="l{i}"/><child link="l{i+1}"/></joint>' for i in range(N))
add("big_chain_20000", robot(body))
# deep xml nesting (stack depth in TinyXML recursive parser)
depth = 100000
add("deep_nesting_100k", '<robot name="r"><link name="a"/>' + "<x>" * depth + "</x>" * depth + "</robot>")



def all_cases() -> list[tuple[str, str]]:
    """(name, URDF text) of every case."""
    return [(name, text) for name, text, _ in cases]
