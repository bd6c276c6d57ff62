// The MJCF grammar of MuJoCo 2.2.2 (see urlab/document/grammar.h for the row format).
//
// Written from the 2.2.2 XML reference and checked against the engine itself by
// tests/document/grammar_test.cc: every element and attribute listed here passes MuJoCo's schema
// check in its context; every attribute name and tag the table knows is refused wherever it is
// not listed; keyword sets are exactly what the reader maps; value counts are exactly what the
// reader enforces; int attributes refuse fractions. Where the engine and the manual disagree the
// engine wins:
//   - <damper> (and default/damper) has no `ctrllimited`: the schema refuses it.
//   - actuators other than <muscle> and <adhesion> accept `refsite`; <general> and <adhesion>
//     accept `body` (adhesion transmission); asset <skin> accepts `group`.
//   - general `gaintype` also accepts "affine"; user sensor `needstage` also accepts "none".
//   - counts the reader does not enforce exactly: solref 1-2, solimp 1-5, gear 1-6, geom/site
//     size 1-3, geom friction 1-3, pair friction 1-5, dyn/gain/biasprm 1-10, fluidcoef 1-5,
//     composite count 1-3, pin coord 1-2.
//   - variable-length arrays (user, key qpos..., mesh vertex...) are written `*`; MuJoCo refuses an
//     empty value for them.
//   - <worldbody> takes no attributes and no joint/freejoint/inertial: the schema shares them
//     with <body>, then the reader refuses them ("World body cannot have ...").
//   - site `type`: the reader maps all geom types, the compiler refuses plane/hfield/mesh; listed
//     here as the five the compiler accepts.
//   - frame sensor `reftype`: MuJoCo silently ignores an unknown value; listed as objtype's set.
//   - tuple element / user sensor `objtype`: the types whose names MuJoCo can look up (mjtObj
//     minus dof and key).
// Quirks of 2.2.2 that the grammar keeps because the schema accepts them:
//   - <equality><distance> passes the schema but the reader refuses it (removed in 2.2.2).
//   - <default><adhesion> passes the schema but its attributes are never read.
//   - composite <joint>/<tendon> `limited` passes the schema but is never read.
// `include` (file relative to the main model file) may stand wherever an element is expected:
// MuJoCo expands it before the schema check; every row with element children lists it.
//
// Row ids: the tag for sections, body contents, assets and actuators ("geom", "mesh",
// "general"); "<parent>.<tag>" where a tag has several contexts or is nested in a section
// ("default.geom", "composite.geom", "equality.joint", "sensor.touch", "spatial.site").
#include <limits>

#include "urlab/document/grammar.h"

namespace urlab::document {

namespace {
constexpr GrammarRow kRows[] = {
    // clang-format off
    {"mujoco", "mujoco", "",
     "include compiler option size visual statistic default custom asset worldbody contact "
     "equality tendon actuator sensor keyframe",
     "model:s"},
    {"include", "include", "",
     "",
     "file:f"},

    // ---------------------------------------------------------------------------------------
    // compiler, option, size, visual, statistic

    {"compiler", "compiler", "",
     "include compiler.lengthrange",
     "autolimits:k{false|true} boundmass:r boundinertia:r settotalmass:r "
     "balanceinertia:k{false|true} strippath:k{false|true} coordinate:k{local|global} "
     "angle:k{radian|degree} fitaabb:k{false|true} eulerseq:s meshdir:s texturedir:s "
     "discardvisual:k{false|true} convexhull:k{false|true} usethread:k{false|true} "
     "fusestatic:k{false|true} inertiafromgeom:k{false|true|auto} inertiagrouprange:i2 "
     "exactmeshinertia:k{false|true}"},
    {"compiler.lengthrange", "lengthrange", "",
     "",
     "mode:k{none|muscle|muscleuser|all} useexisting:k{false|true} uselimit:k{false|true} "
     "accel:r maxforce:r timeconst:r timestep:r inttotal:r inteval:r tolrange:r"},
    {"option", "option", "",
     "include option.flag",
     "timestep:r apirate:r impratio:r tolerance:r noslip_tolerance:r mpr_tolerance:r "
     "gravity:r3 wind:r3 magnetic:r3 density:r viscosity:r o_margin:r o_solref:r1-2 "
     "o_solimp:r1-5 integrator:k{Euler|RK4|implicit} collision:k{all|predefined|dynamic} "
     "cone:k{pyramidal|elliptic} jacobian:k{dense|sparse|auto} solver:k{PGS|CG|Newton} "
     "iterations:i noslip_iterations:i mpr_iterations:i"},
    {"option.flag", "flag", "",
     "",
     "constraint:k{disable|enable} equality:k{disable|enable} frictionloss:k{disable|enable} "
     "limit:k{disable|enable} contact:k{disable|enable} passive:k{disable|enable} "
     "gravity:k{disable|enable} clampctrl:k{disable|enable} warmstart:k{disable|enable} "
     "filterparent:k{disable|enable} actuation:k{disable|enable} refsafe:k{disable|enable} "
     "sensor:k{disable|enable} override:k{disable|enable} energy:k{disable|enable} "
     "fwdinv:k{disable|enable} sensornoise:k{disable|enable} multiccd:k{disable|enable}"},
    {"size", "size", "",
     "",
     "njmax:i nconmax:i nstack:i nuserdata:i nkey:i nuser_body:i nuser_jnt:i nuser_geom:i "
     "nuser_site:i nuser_cam:i nuser_tendon:i nuser_actuator:i nuser_sensor:i"},
    {"visual", "visual", "",
     "include visual.global visual.quality visual.headlight visual.map visual.scale "
     "visual.rgba",
     ""},
    {"visual.global", "global", "",
     "",
     "fovy:r ipd:r azimuth:r elevation:r linewidth:r glow:r offwidth:i offheight:i"},
    {"visual.quality", "quality", "",
     "",
     "shadowsize:i offsamples:i numslices:i numstacks:i numquads:i"},
    {"visual.headlight", "headlight", "",
     "",
     "ambient:r3 diffuse:r3 specular:r3 active:i"},
    {"visual.map", "map", "",
     "",
     "stiffness:r stiffnessrot:r force:r torque:r alpha:r fogstart:r fogend:r znear:r zfar:r "
     "haze:r shadowclip:r shadowscale:r actuatortendon:r"},
    {"visual.scale", "scale", "",
     "",
     "forcewidth:r contactwidth:r contactheight:r connect:r com:r camera:r light:r "
     "selectpoint:r jointlength:r jointwidth:r actuatorlength:r actuatorwidth:r framelength:r "
     "framewidth:r constraint:r slidercrank:r"},
    {"visual.rgba", "rgba", "",
     "",
     "fog:r4 haze:r4 force:r4 inertia:r4 joint:r4 actuator:r4 actuatornegative:r4 "
     "actuatorpositive:r4 com:r4 camera:r4 light:r4 selectpoint:r4 connect:r4 contactpoint:r4 "
     "contactforce:r4 contactfriction:r4 contacttorque:r4 contactgap:r4 rangefinder:r4 "
     "constraint:r4 slidercrank:r4 crankbroken:r4"},
    {"statistic", "statistic", "",
     "",
     "meaninertia:r meanmass:r meansize:r extent:r center:r3"},

    // ---------------------------------------------------------------------------------------
    // default (recursive); its children carry neither name nor class

    {"default", "default", "class",
     "include default default.mesh default.material default.joint default.geom default.site "
     "default.camera default.light default.pair default.equality default.tendon "
     "default.general default.motor default.position default.velocity default.intvelocity "
     "default.damper default.cylinder default.muscle default.adhesion",
     "class:s"},
    {"default.mesh", "mesh", "",
     "",
     "scale:r3"},
    {"default.material", "material", "",
     "",
     "texture:s@texture emission:r specular:r shininess:r reflectance:r rgba:r4 texrepeat:r2 "
     "texuniform:k{false|true}"},
    {"default.joint", "joint", "",
     "",
     "type:k{free|ball|slide|hinge} group:i pos:r3 axis:r3 springdamper:r2 "
     "limited:k{false|true|auto} solreflimit:r1-2 solimplimit:r1-5 solreffriction:r1-2 "
     "solimpfriction:r1-5 stiffness:r range:r2 margin:r ref:r springref:r armature:r damping:r "
     "frictionloss:r user:r*"},
    {"default.geom", "geom", "",
     "",
     "type:k{plane|hfield|sphere|capsule|ellipsoid|cylinder|box|mesh} contype:i conaffinity:i "
     "condim:i group:i priority:i size:r1-3 material:s@material friction:r1-3 mass:r density:r "
     "shellinertia:k{false|true} solmix:r solref:r1-2 solimp:r1-5 margin:r gap:r fromto:r6 "
     "pos:r3 quat:r4 axisangle:r4 xyaxes:r6 zaxis:r3 euler:r3 hfield:s@hfield mesh:s@mesh "
     "fitscale:r rgba:r4 fluidshape:k{none|ellipsoid} fluidcoef:r1-5 user:r*"},
    {"default.site", "site", "",
     "",
     "type:k{sphere|capsule|ellipsoid|cylinder|box} group:i material:s@material size:r1-3 "
     "fromto:r6 pos:r3 quat:r4 axisangle:r4 xyaxes:r6 zaxis:r3 euler:r3 rgba:r4 user:r*"},
    {"default.camera", "camera", "",
     "",
     "mode:k{fixed|track|trackcom|targetbody|targetbodycom} fovy:r ipd:r pos:r3 quat:r4 "
     "axisangle:r4 xyaxes:r6 zaxis:r3 euler:r3 user:r*"},
    {"default.light", "light", "",
     "",
     "mode:k{fixed|track|trackcom|targetbody|targetbodycom} directional:k{false|true} "
     "castshadow:k{false|true} active:k{false|true} pos:r3 dir:r3 attenuation:r3 cutoff:r "
     "exponent:r ambient:r3 diffuse:r3 specular:r3"},
    {"default.pair", "pair", "",
     "",
     "condim:i friction:r1-5 solref:r1-2 solimp:r1-5 gap:r margin:r"},
    {"default.equality", "equality", "",
     "",
     "active:k{false|true} solref:r1-2 solimp:r1-5"},
    {"default.tendon", "tendon", "",
     "",
     "group:i limited:k{false|true|auto} range:r2 solreflimit:r1-2 solimplimit:r1-5 "
     "solreffriction:r1-2 solimpfriction:r1-5 frictionloss:r springlength:r width:r "
     "material:s@material margin:r stiffness:r damping:r rgba:r4 user:r*"},
    {"default.general", "general", "",
     "",
     "ctrllimited:k{false|true|auto} forcelimited:k{false|true|auto} "
     "actlimited:k{false|true|auto} ctrlrange:r2 forcerange:r2 actrange:r2 gear:r1-6 "
     "cranklength:r user:r* group:i dyntype:k{none|integrator|filter|muscle|user} "
     "gaintype:k{fixed|affine|muscle|user} biastype:k{none|affine|muscle|user} dynprm:r1-10 "
     "gainprm:r1-10 biasprm:r1-10"},
    {"default.motor", "motor", "",
     "",
     "ctrllimited:k{false|true|auto} forcelimited:k{false|true|auto} ctrlrange:r2 "
     "forcerange:r2 gear:r1-6 cranklength:r user:r* group:i"},
    {"default.position", "position", "",
     "",
     "ctrllimited:k{false|true|auto} forcelimited:k{false|true|auto} ctrlrange:r2 "
     "forcerange:r2 gear:r1-6 cranklength:r user:r* group:i kp:r"},
    {"default.velocity", "velocity", "",
     "",
     "ctrllimited:k{false|true|auto} forcelimited:k{false|true|auto} ctrlrange:r2 "
     "forcerange:r2 gear:r1-6 cranklength:r user:r* group:i kv:r"},
    {"default.intvelocity", "intvelocity", "",
     "",
     "ctrllimited:k{false|true|auto} forcelimited:k{false|true|auto} ctrlrange:r2 "
     "forcerange:r2 gear:r1-6 cranklength:r user:r* group:i kp:r actrange:r2"},
    {"default.damper", "damper", "",  // no ctrllimited in 2.2.2
     "",
     "forcelimited:k{false|true|auto} ctrlrange:r2 forcerange:r2 gear:r1-6 cranklength:r "
     "user:r* group:i kv:r"},
    {"default.cylinder", "cylinder", "",
     "",
     "ctrllimited:k{false|true|auto} forcelimited:k{false|true|auto} ctrlrange:r2 "
     "forcerange:r2 gear:r1-6 cranklength:r user:r* group:i timeconst:r area:r diameter:r "
     "bias:r3"},
    {"default.muscle", "muscle", "",
     "",
     "ctrllimited:k{false|true|auto} forcelimited:k{false|true|auto} ctrlrange:r2 "
     "forcerange:r2 gear:r1-6 cranklength:r user:r* group:i timeconst:r2 range:r2 force:r "
     "scale:r lmin:r lmax:r vmax:r fpmax:r fvmax:r"},
    {"default.adhesion", "adhesion", "",  // accepted, but 2.2.2 never reads these values
     "",
     "forcelimited:k{false|true|auto} ctrlrange:r2 forcerange:r2 gain:r user:r* group:i"},

    // ---------------------------------------------------------------------------------------
    // custom

    {"custom", "custom", "",
     "include custom.numeric custom.text custom.tuple",
     ""},
    {"custom.numeric", "numeric", "numeric",
     "",
     "name:s size:i data:r*"},
    {"custom.text", "text", "text",
     "",
     "name:s data:s"},
    {"custom.tuple", "tuple", "tuple",
     "include tuple.element",
     "name:s"},
    {"tuple.element", "element", "",
     "",
     "objtype:k{body|xbody|joint|geom|site|camera|light|mesh|skin|hfield|texture|material|pair|"
     "exclude|equality|tendon|actuator|sensor|numeric|text|tuple} "
     "objname:s@obj:objtype prm:r"},

    // ---------------------------------------------------------------------------------------
    // asset

    {"asset", "asset", "",
     "include texture hfield mesh skin material",
     ""},
    {"texture", "texture", "texture",
     "",
     "name:s type:k{2d|cube|skybox} file:t gridsize:i2 gridlayout:s fileright:t fileleft:t "
     "fileup:t filedown:t filefront:t fileback:t builtin:k{none|gradient|checker|flat} rgb1:r3 "
     "rgb2:r3 mark:k{none|edge|cross|random} markrgb:r3 random:r width:i height:i "
     "hflip:k{false|true} vflip:k{false|true}"},
    {"hfield", "hfield", "hfield",
     "",
     "name:s file:m nrow:i ncol:i size:r4"},
    {"mesh", "mesh", "mesh",
     "",
     "name:s class:s@class file:m vertex:r* normal:r* texcoord:r* face:i* refpos:r3 refquat:r4 "
     "scale:r3 smoothnormal:k{false|true}"},
    {"skin", "skin", "skin",
     "include skin.bone",
     "name:s file:m material:s@material rgba:r4 inflate:r vertex:r* texcoord:r* face:i* "
     "group:i"},
    {"skin.bone", "bone", "",
     "",
     "body:s@body bindpos:r3 bindquat:r4 vertid:i* vertweight:r*"},
    {"material", "material", "material",
     "",
     "name:s class:s@class texture:s@texture texrepeat:r2 texuniform:k{false|true} emission:r "
     "specular:r shininess:r reflectance:r rgba:r4"},

    // ---------------------------------------------------------------------------------------
    // worldbody, body (recursive) and what bodies contain

    {"worldbody", "worldbody", "",  // no attributes, no joint/freejoint/inertial
     "include body geom site camera light composite",
     ""},
    {"body", "body", "body",
     "include body inertial joint freejoint geom site camera light composite",
     "name:s childclass:s@class pos:r3 quat:r4 mocap:k{false|true} axisangle:r4 xyaxes:r6 "
     "zaxis:r3 euler:r3 user:r*"},
    {"inertial", "inertial", "",
     "",
     "pos:r3 quat:r4 mass:r diaginertia:r3 axisangle:r4 xyaxes:r6 zaxis:r3 euler:r3 "
     "fullinertia:r6"},
    {"joint", "joint", "joint",
     "",
     "name:s class:s@class type:k{free|ball|slide|hinge} group:i pos:r3 axis:r3 "
     "springdamper:r2 limited:k{false|true|auto} solreflimit:r1-2 solimplimit:r1-5 "
     "solreffriction:r1-2 solimpfriction:r1-5 stiffness:r range:r2 margin:r ref:r springref:r "
     "armature:r damping:r frictionloss:r user:r*"},
    {"freejoint", "freejoint", "joint",
     "",
     "name:s group:i"},
    {"geom", "geom", "geom",
     "",
     "name:s class:s@class type:k{plane|hfield|sphere|capsule|ellipsoid|cylinder|box|mesh} "
     "contype:i conaffinity:i condim:i group:i priority:i size:r1-3 material:s@material "
     "friction:r1-3 mass:r density:r shellinertia:k{false|true} solmix:r solref:r1-2 "
     "solimp:r1-5 margin:r gap:r fromto:r6 pos:r3 quat:r4 axisangle:r4 xyaxes:r6 zaxis:r3 "
     "euler:r3 hfield:s@hfield mesh:s@mesh fitscale:r rgba:r4 fluidshape:k{none|ellipsoid} "
     "fluidcoef:r1-5 user:r*"},
    {"site", "site", "site",
     "",
     "name:s class:s@class type:k{sphere|capsule|ellipsoid|cylinder|box} group:i "
     "material:s@material size:r1-3 fromto:r6 pos:r3 quat:r4 axisangle:r4 xyaxes:r6 zaxis:r3 "
     "euler:r3 rgba:r4 user:r*"},
    {"camera", "camera", "camera",
     "",
     "name:s class:s@class mode:k{fixed|track|trackcom|targetbody|targetbodycom} target:s@body "
     "fovy:r ipd:r pos:r3 quat:r4 axisangle:r4 xyaxes:r6 zaxis:r3 euler:r3 user:r*"},
    {"light", "light", "light",
     "",
     "name:s class:s@class mode:k{fixed|track|trackcom|targetbody|targetbodycom} target:s@body "
     "directional:k{false|true} castshadow:k{false|true} active:k{false|true} pos:r3 dir:r3 "
     "attenuation:r3 cutoff:r exponent:r ambient:r3 diffuse:r3 specular:r3"},
    {"composite", "composite", "",
     "include composite.joint composite.tendon composite.skin composite.geom composite.site "
     "composite.pin",
     "prefix:s type:k{particle|grid|rope|loop|cloth|box|cylinder|ellipsoid} count:i1-3 "
     "spacing:r offset:r3 flatinertia:r solrefsmooth:r1-2 solimpsmooth:r1-5"},
    {"composite.joint", "joint", "",  // `limited` is accepted but never read by 2.2.2
     "",
     "kind:k{main|twist|stretch} group:i stiffness:r damping:r armature:r solreffix:r1-2 "
     "solimpfix:r1-5 limited:k{false|true|auto} range:r2 margin:r solreflimit:r1-2 "
     "solimplimit:r1-5 frictionloss:r solreffriction:r1-2 solimpfriction:r1-5"},
    {"composite.tendon", "tendon", "",  // `limited` is accepted but never read by 2.2.2
     "",
     "kind:k{main|shear} group:i stiffness:r damping:r solreffix:r1-2 solimpfix:r1-5 "
     "limited:k{false|true|auto} range:r2 margin:r solreflimit:r1-2 solimplimit:r1-5 "
     "frictionloss:r solreffriction:r1-2 solimpfriction:r1-5 material:s@material rgba:r4 "
     "width:r"},
    {"composite.skin", "skin", "",
     "",
     "texcoord:k{false|true} material:s@material rgba:r4 inflate:r subgrid:i group:i"},
    {"composite.geom", "geom", "",
     "",
     "type:k{plane|hfield|sphere|capsule|ellipsoid|cylinder|box|mesh} contype:i conaffinity:i "
     "condim:i group:i priority:i size:r1-3 material:s@material rgba:r4 friction:r1-3 mass:r "
     "density:r solmix:r solref:r1-2 solimp:r1-5 margin:r gap:r"},
    {"composite.site", "site", "",
     "",
     "group:i size:r1-3 material:s@material rgba:r4"},
    {"composite.pin", "pin", "",
     "",
     "coord:i1-2"},

    // ---------------------------------------------------------------------------------------
    // contact, equality

    {"contact", "contact", "",
     "include contact.pair contact.exclude",
     ""},
    {"contact.pair", "pair", "pair",
     "",
     "name:s class:s@class geom1:s@geom geom2:s@geom condim:i friction:r1-5 solref:r1-2 "
     "solimp:r1-5 gap:r margin:r"},
    {"contact.exclude", "exclude", "exclude",
     "",
     "name:s body1:s@body body2:s@body"},
    {"equality", "equality", "",
     "include equality.connect equality.weld equality.joint equality.tendon equality.distance",
     ""},
    {"equality.connect", "connect", "equality",
     "",
     "name:s class:s@class body1:s@body body2:s@body anchor:r3 active:k{false|true} "
     "solref:r1-2 solimp:r1-5"},
    {"equality.weld", "weld", "equality",
     "",
     "name:s class:s@class body1:s@body body2:s@body relpose:r7 anchor:r3 torquescale:r "
     "active:k{false|true} solref:r1-2 solimp:r1-5"},
    {"equality.joint", "joint", "equality",
     "",
     "name:s class:s@class joint1:s@joint joint2:s@joint polycoef:r5 active:k{false|true} "
     "solref:r1-2 solimp:r1-5"},
    {"equality.tendon", "tendon", "equality",
     "",
     "name:s class:s@class tendon1:s@tendon tendon2:s@tendon polycoef:r5 active:k{false|true} "
     "solref:r1-2 solimp:r1-5"},
    {"equality.distance", "distance", "equality",  // schema only: the 2.2.2 reader refuses it
     "",
     "name:s class:s@class geom1:s@geom geom2:s@geom distance:r active:k{false|true} "
     "solref:r1-2 solimp:r1-5"},

    // ---------------------------------------------------------------------------------------
    // tendon

    {"tendon", "tendon", "",
     "include tendon.spatial tendon.fixed",
     ""},
    {"tendon.spatial", "spatial", "tendon",
     "include spatial.site spatial.geom spatial.pulley",
     "name:s class:s@class group:i limited:k{false|true|auto} range:r2 solreflimit:r1-2 "
     "solimplimit:r1-5 solreffriction:r1-2 solimpfriction:r1-5 frictionloss:r springlength:r "
     "width:r material:s@material margin:r stiffness:r damping:r rgba:r4 user:r*"},
    {"spatial.site", "site", "",
     "",
     "site:s@site"},
    {"spatial.geom", "geom", "",
     "",
     "geom:s@geom sidesite:s@site"},
    {"spatial.pulley", "pulley", "",
     "",
     "divisor:r"},
    {"tendon.fixed", "fixed", "tendon",
     "include fixed.joint",
     "name:s class:s@class group:i limited:k{false|true|auto} range:r2 solreflimit:r1-2 "
     "solimplimit:r1-5 solreffriction:r1-2 solimpfriction:r1-5 frictionloss:r springlength:r "
     "margin:r stiffness:r damping:r user:r*"},
    {"fixed.joint", "joint", "",
     "",
     "joint:s@joint coef:r"},

    // ---------------------------------------------------------------------------------------
    // actuator

    {"actuator", "actuator", "",
     "include general motor position velocity intvelocity damper cylinder muscle adhesion",
     ""},
    {"general", "general", "actuator",
     "",
     "name:s class:s@class group:i ctrllimited:k{false|true|auto} "
     "forcelimited:k{false|true|auto} actlimited:k{false|true|auto} ctrlrange:r2 forcerange:r2 "
     "actrange:r2 lengthrange:r2 gear:r1-6 cranklength:r joint:s@joint jointinparent:s@joint "
     "tendon:s@tendon site:s@site refsite:s@site cranksite:s@site slidersite:s@site "
     "body:s@body user:r* dyntype:k{none|integrator|filter|muscle|user} "
     "gaintype:k{fixed|affine|muscle|user} biastype:k{none|affine|muscle|user} dynprm:r1-10 "
     "gainprm:r1-10 biasprm:r1-10"},
    {"motor", "motor", "actuator",
     "",
     "name:s class:s@class group:i ctrllimited:k{false|true|auto} "
     "forcelimited:k{false|true|auto} ctrlrange:r2 forcerange:r2 lengthrange:r2 gear:r1-6 "
     "cranklength:r joint:s@joint jointinparent:s@joint tendon:s@tendon site:s@site "
     "refsite:s@site cranksite:s@site slidersite:s@site user:r*"},
    {"position", "position", "actuator",
     "",
     "name:s class:s@class group:i ctrllimited:k{false|true|auto} "
     "forcelimited:k{false|true|auto} ctrlrange:r2 forcerange:r2 lengthrange:r2 gear:r1-6 "
     "cranklength:r joint:s@joint jointinparent:s@joint tendon:s@tendon site:s@site "
     "refsite:s@site cranksite:s@site slidersite:s@site user:r* kp:r"},
    {"velocity", "velocity", "actuator",
     "",
     "name:s class:s@class group:i ctrllimited:k{false|true|auto} "
     "forcelimited:k{false|true|auto} ctrlrange:r2 forcerange:r2 lengthrange:r2 gear:r1-6 "
     "cranklength:r joint:s@joint jointinparent:s@joint tendon:s@tendon site:s@site "
     "refsite:s@site cranksite:s@site slidersite:s@site user:r* kv:r"},
    {"intvelocity", "intvelocity", "actuator",
     "",
     "name:s class:s@class group:i ctrllimited:k{false|true|auto} "
     "forcelimited:k{false|true|auto} ctrlrange:r2 forcerange:r2 actrange:r2 lengthrange:r2 "
     "gear:r1-6 cranklength:r joint:s@joint jointinparent:s@joint tendon:s@tendon site:s@site "
     "refsite:s@site cranksite:s@site slidersite:s@site user:r* kp:r"},
    {"damper", "damper", "actuator",  // no ctrllimited in 2.2.2
     "",
     "name:s class:s@class group:i forcelimited:k{false|true|auto} ctrlrange:r2 forcerange:r2 "
     "lengthrange:r2 gear:r1-6 cranklength:r joint:s@joint jointinparent:s@joint "
     "tendon:s@tendon site:s@site refsite:s@site cranksite:s@site slidersite:s@site user:r* "
     "kv:r"},
    {"cylinder", "cylinder", "actuator",
     "",
     "name:s class:s@class group:i ctrllimited:k{false|true|auto} "
     "forcelimited:k{false|true|auto} ctrlrange:r2 forcerange:r2 lengthrange:r2 gear:r1-6 "
     "cranklength:r joint:s@joint jointinparent:s@joint tendon:s@tendon site:s@site "
     "refsite:s@site cranksite:s@site slidersite:s@site user:r* timeconst:r area:r diameter:r "
     "bias:r3"},
    {"muscle", "muscle", "actuator",  // no site/refsite in 2.2.2
     "",
     "name:s class:s@class group:i ctrllimited:k{false|true|auto} "
     "forcelimited:k{false|true|auto} ctrlrange:r2 forcerange:r2 lengthrange:r2 gear:r1-6 "
     "cranklength:r joint:s@joint jointinparent:s@joint tendon:s@tendon cranksite:s@site "
     "slidersite:s@site user:r* timeconst:r2 range:r2 force:r scale:r lmin:r lmax:r vmax:r "
     "fpmax:r fvmax:r"},
    {"adhesion", "adhesion", "actuator",
     "",
     "name:s class:s@class group:i forcelimited:k{false|true|auto} ctrlrange:r2 forcerange:r2 "
     "body:s@body gain:r user:r*"},

    // ---------------------------------------------------------------------------------------
    // sensor

    {"sensor", "sensor", "",
     "include sensor.touch sensor.accelerometer sensor.velocimeter sensor.gyro sensor.force "
     "sensor.torque sensor.magnetometer sensor.rangefinder sensor.jointpos sensor.jointvel "
     "sensor.tendonpos sensor.tendonvel sensor.actuatorpos sensor.actuatorvel "
     "sensor.actuatorfrc sensor.ballquat sensor.ballangvel sensor.jointlimitpos "
     "sensor.jointlimitvel sensor.jointlimitfrc sensor.tendonlimitpos sensor.tendonlimitvel "
     "sensor.tendonlimitfrc sensor.framepos sensor.framequat sensor.framexaxis "
     "sensor.frameyaxis sensor.framezaxis sensor.framelinvel sensor.frameangvel "
     "sensor.framelinacc sensor.frameangacc sensor.subtreecom sensor.subtreelinvel "
     "sensor.subtreeangmom sensor.clock sensor.user",
     ""},
    {"sensor.touch", "touch", "sensor",
     "",
     "name:s site:s@site noise:r cutoff:r user:r*"},
    {"sensor.accelerometer", "accelerometer", "sensor",
     "",
     "name:s site:s@site noise:r cutoff:r user:r*"},
    {"sensor.velocimeter", "velocimeter", "sensor",
     "",
     "name:s site:s@site noise:r cutoff:r user:r*"},
    {"sensor.gyro", "gyro", "sensor",
     "",
     "name:s site:s@site noise:r cutoff:r user:r*"},
    {"sensor.force", "force", "sensor",
     "",
     "name:s site:s@site noise:r cutoff:r user:r*"},
    {"sensor.torque", "torque", "sensor",
     "",
     "name:s site:s@site noise:r cutoff:r user:r*"},
    {"sensor.magnetometer", "magnetometer", "sensor",
     "",
     "name:s site:s@site noise:r cutoff:r user:r*"},
    {"sensor.rangefinder", "rangefinder", "sensor",
     "",
     "name:s site:s@site noise:r cutoff:r user:r*"},
    {"sensor.jointpos", "jointpos", "sensor",
     "",
     "name:s joint:s@joint noise:r cutoff:r user:r*"},
    {"sensor.jointvel", "jointvel", "sensor",
     "",
     "name:s joint:s@joint noise:r cutoff:r user:r*"},
    {"sensor.tendonpos", "tendonpos", "sensor",
     "",
     "name:s tendon:s@tendon noise:r cutoff:r user:r*"},
    {"sensor.tendonvel", "tendonvel", "sensor",
     "",
     "name:s tendon:s@tendon noise:r cutoff:r user:r*"},
    {"sensor.actuatorpos", "actuatorpos", "sensor",
     "",
     "name:s actuator:s@actuator noise:r cutoff:r user:r*"},
    {"sensor.actuatorvel", "actuatorvel", "sensor",
     "",
     "name:s actuator:s@actuator noise:r cutoff:r user:r*"},
    {"sensor.actuatorfrc", "actuatorfrc", "sensor",
     "",
     "name:s actuator:s@actuator noise:r cutoff:r user:r*"},
    {"sensor.ballquat", "ballquat", "sensor",
     "",
     "name:s joint:s@joint noise:r cutoff:r user:r*"},
    {"sensor.ballangvel", "ballangvel", "sensor",
     "",
     "name:s joint:s@joint noise:r cutoff:r user:r*"},
    {"sensor.jointlimitpos", "jointlimitpos", "sensor",
     "",
     "name:s joint:s@joint noise:r cutoff:r user:r*"},
    {"sensor.jointlimitvel", "jointlimitvel", "sensor",
     "",
     "name:s joint:s@joint noise:r cutoff:r user:r*"},
    {"sensor.jointlimitfrc", "jointlimitfrc", "sensor",
     "",
     "name:s joint:s@joint noise:r cutoff:r user:r*"},
    {"sensor.tendonlimitpos", "tendonlimitpos", "sensor",
     "",
     "name:s tendon:s@tendon noise:r cutoff:r user:r*"},
    {"sensor.tendonlimitvel", "tendonlimitvel", "sensor",
     "",
     "name:s tendon:s@tendon noise:r cutoff:r user:r*"},
    {"sensor.tendonlimitfrc", "tendonlimitfrc", "sensor",
     "",
     "name:s tendon:s@tendon noise:r cutoff:r user:r*"},
    {"sensor.framepos", "framepos", "sensor",
     "",
     "name:s objtype:k{body|xbody|geom|site|camera} objname:s@obj:objtype "
     "reftype:k{body|xbody|geom|site|camera} refname:s@obj:reftype noise:r cutoff:r user:r*"},
    {"sensor.framequat", "framequat", "sensor",
     "",
     "name:s objtype:k{body|xbody|geom|site|camera} objname:s@obj:objtype "
     "reftype:k{body|xbody|geom|site|camera} refname:s@obj:reftype noise:r cutoff:r user:r*"},
    {"sensor.framexaxis", "framexaxis", "sensor",
     "",
     "name:s objtype:k{body|xbody|geom|site|camera} objname:s@obj:objtype "
     "reftype:k{body|xbody|geom|site|camera} refname:s@obj:reftype noise:r cutoff:r user:r*"},
    {"sensor.frameyaxis", "frameyaxis", "sensor",
     "",
     "name:s objtype:k{body|xbody|geom|site|camera} objname:s@obj:objtype "
     "reftype:k{body|xbody|geom|site|camera} refname:s@obj:reftype noise:r cutoff:r user:r*"},
    {"sensor.framezaxis", "framezaxis", "sensor",
     "",
     "name:s objtype:k{body|xbody|geom|site|camera} objname:s@obj:objtype "
     "reftype:k{body|xbody|geom|site|camera} refname:s@obj:reftype noise:r cutoff:r user:r*"},
    {"sensor.framelinvel", "framelinvel", "sensor",
     "",
     "name:s objtype:k{body|xbody|geom|site|camera} objname:s@obj:objtype "
     "reftype:k{body|xbody|geom|site|camera} refname:s@obj:reftype noise:r cutoff:r user:r*"},
    {"sensor.frameangvel", "frameangvel", "sensor",
     "",
     "name:s objtype:k{body|xbody|geom|site|camera} objname:s@obj:objtype "
     "reftype:k{body|xbody|geom|site|camera} refname:s@obj:reftype noise:r cutoff:r user:r*"},
    {"sensor.framelinacc", "framelinacc", "sensor",
     "",
     "name:s objtype:k{body|xbody|geom|site|camera} objname:s@obj:objtype noise:r cutoff:r "
     "user:r*"},
    {"sensor.frameangacc", "frameangacc", "sensor",
     "",
     "name:s objtype:k{body|xbody|geom|site|camera} objname:s@obj:objtype noise:r cutoff:r "
     "user:r*"},
    {"sensor.subtreecom", "subtreecom", "sensor",
     "",
     "name:s body:s@body noise:r cutoff:r user:r*"},
    {"sensor.subtreelinvel", "subtreelinvel", "sensor",
     "",
     "name:s body:s@body noise:r cutoff:r user:r*"},
    {"sensor.subtreeangmom", "subtreeangmom", "sensor",
     "",
     "name:s body:s@body noise:r cutoff:r user:r*"},
    {"sensor.clock", "clock", "sensor",
     "",
     "name:s noise:r cutoff:r user:r*"},
    {"sensor.user", "user", "sensor",
     "",
     "name:s "
     "objtype:k{body|xbody|joint|geom|site|camera|light|mesh|skin|hfield|texture|material|pair|"
     "exclude|equality|tendon|actuator|sensor|numeric|text|tuple} "
     "objname:s@obj:objtype datatype:k{real|positive|axis|quaternion} "
     "needstage:k{pos|vel|acc|none} dim:i noise:r cutoff:r user:r*"},

    // ---------------------------------------------------------------------------------------
    // keyframe

    {"keyframe", "keyframe", "",
     "include key",
     ""},
    {"key", "key", "key",
     "",
     "name:s time:r qpos:r* qvel:r* act:r* ctrl:r* mpos:r* mquat:r*"},
    // clang-format on
};
}  // namespace

std::span<const GrammarRow> GrammarTable() { return kRows; }

namespace {
constexpr double kMaxReal = std::numeric_limits<double>::max();  // finite: refuses inf
constexpr double kMaxInt = std::numeric_limits<int>::max();
// Sizes default to -1 ("as needed"); anything below is meaningless.
#define URLAB_SIZE_ROW(attr) \
  { "size", attr, -1, false, kMaxInt }
constexpr RangeRow kRanges[] = {
    {"option", "timestep", 0, true, kMaxReal},  // > 0 and finite
    {"option", "apirate", 0, false, kMaxReal},
    {"option", "impratio", 0, true, kMaxReal},
    {"option", "tolerance", 0, false, kMaxReal},
    {"option", "noslip_tolerance", 0, false, kMaxReal},
    {"option", "mpr_tolerance", 0, false, kMaxReal},
    {"option", "density", 0, false, kMaxReal},
    {"option", "viscosity", 0, false, kMaxReal},
    {"option", "iterations", 0, false, kMaxInt},
    {"option", "noslip_iterations", 0, false, kMaxInt},
    {"option", "mpr_iterations", 0, false, kMaxInt},
    URLAB_SIZE_ROW("njmax"),
    URLAB_SIZE_ROW("nconmax"),
    URLAB_SIZE_ROW("nstack"),
    URLAB_SIZE_ROW("nuserdata"),
    URLAB_SIZE_ROW("nkey"),
    URLAB_SIZE_ROW("nuser_body"),
    URLAB_SIZE_ROW("nuser_jnt"),
    URLAB_SIZE_ROW("nuser_geom"),
    URLAB_SIZE_ROW("nuser_site"),
    URLAB_SIZE_ROW("nuser_cam"),
    URLAB_SIZE_ROW("nuser_tendon"),
    URLAB_SIZE_ROW("nuser_actuator"),
    URLAB_SIZE_ROW("nuser_sensor"),
};
#undef URLAB_SIZE_ROW
}  // namespace

std::span<const RangeRow> ValueRangeTable() { return kRanges; }

}  // namespace urlab::document
