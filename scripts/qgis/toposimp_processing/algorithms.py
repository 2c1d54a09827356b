"""The toposimp commands as Processing algorithms.

Each algorithm resolves its parameters to files (a layer that is not a file toposimp can read,
or that has a selection, is exported to a temporary GeoPackage by QGIS), builds the command line
with cli_args, runs it with runner (progress and cancellation through `feedback`) and returns the
output with the numbers of toposimp's --json summary."""

import json
import os

from qgis.core import (
    QgsProcessing,
    QgsProcessingAlgorithm,
    QgsProcessingContext,
    QgsProcessingException,
    QgsProcessingOutputBoolean,
    QgsProcessingOutputNumber,
    QgsProcessingOutputString,
    QgsProcessingParameterBand,
    QgsProcessingParameterBoolean,
    QgsProcessingParameterDefinition,
    QgsProcessingParameterEnum,
    QgsProcessingParameterFeatureSource,
    QgsProcessingParameterField,
    QgsProcessingParameterFile,
    QgsProcessingParameterFileDestination,
    QgsProcessingParameterNumber,
    QgsProcessingParameterRasterLayer,
    QgsProcessingParameterVectorDestination,
)

from . import cli_args, runner, settings

# Formats toposimp reads directly; anything else (memory layers, databases, selections) is
# exported by QGIS to a temporary GeoPackage first.
READABLE_VECTOR_FORMATS = ["gpkg", "shp", "geojson", "json", "fgb", "gml", "kml", "sqlite", "tab", "mif", "csv"]


def _advanced(parameter):
    parameter.setFlags(parameter.flags() | QgsProcessingParameterDefinition.FlagAdvanced)
    return parameter


class ToposimpAlgorithm(QgsProcessingAlgorithm):
    """What the algorithms share: their description (class attributes), running the executable,
    and turning its failures into Processing errors with toposimp's own message."""

    NAME = DISPLAY_NAME = GROUP = GROUP_ID = HELP = ""

    def createInstance(self):
        return type(self)()

    def name(self):
        return self.NAME

    def displayName(self):
        return self.DISPLAY_NAME

    def group(self):
        return self.GROUP

    def groupId(self):
        return self.GROUP_ID

    def shortHelpString(self):
        return self.HELP

    def icon(self):
        return settings.icon()

    def run_toposimp(self, args, feedback):
        try:
            executable = runner.find_executable(settings.configured_executable())
            code, stdout = runner.run(executable, args, feedback)
        except runner.ExecutableNotFound as error:
            raise QgsProcessingException(str(error))
        except runner.Cancelled:
            feedback.pushInfo("cancelled: toposimp was stopped and left no output")
            return None, {}
        except runner.ToolError as error:
            raise QgsProcessingException("toposimp: " + str(error))
        summary = runner.parse_summary(stdout)
        if summary:
            feedback.pushInfo("summary: " + json.dumps(summary))
        return code, summary

    def optional_int(self, parameters, name, context):
        return self.parameterAsInt(parameters, name, context) if parameters.get(name) is not None else None

    def optional_double(self, parameters, name, context):
        return self.parameterAsDouble(parameters, name, context) if parameters.get(name) is not None else None

    def source_file(self, parameters, name, context, feedback):
        """(path, layer name or None) of a feature source parameter, exporting it if needed."""
        if parameters.get(name) is None:
            return None, None
        path, layer = self.parameterAsCompatibleSourceLayerPathAndLayerName(
            parameters, name, context, READABLE_VECTOR_FORMATS, "gpkg", feedback)
        return path, (layer or None)

    @staticmethod
    def whole_file_destination(destination):
        """toposimp writes whole files: a destination that adds a layer to an existing
        GeoPackage would replace the file and lose its other layers, so it is refused."""
        path, layer = cli_args.split_destination(destination)
        if layer and os.path.exists(path):
            raise QgsProcessingException(
                "toposimp writes whole files and would replace '{}' with its other layers; "
                "choose a new file".format(path))
        return path, layer


class MapAlgorithm(ToposimpAlgorithm):
    NAME = "map"
    DISPLAY_NAME = "Simplify lines and polygons (topology-preserving)"
    GROUP = "Maps"
    GROUP_ID = "maps"
    HELP = ("Visvalingam-Whyatt simplification that never changes topology: a vertex is removed only if "
            "no other vertex and no control point lies in its triangle, decided with exact predicates. "
            "Polygons sharing borders stay a coverage (each border simplified once); lines that cross "
            "keep their crossings; control points (e.g. cities) stay on their side of every line and "
            "in their polygon. Attributes, CRS and feature order are kept.\n\n"
            "Stop when: a share of the vertices is left (Share, %), N vertices are left or removed "
            "(N), every vertex with effective area up to A is gone (A), or nothing more can go.\n"
            "Validate runs toposimp check on the result before writing it; on a violation nothing "
            "is written and the algorithm fails.\n"
            "Round to D decimals (or, advanced, to a grid step) puts every written coordinate on that "
            "grid with the same promises; a location no grid point near it can serve stays where it "
            "is, with a warning. Advanced: weighted effective area (mapshaper's weighting) and areas "
            "on the sphere only change the order in which vertices go.")

    def initAlgorithm(self, config=None):
        self.addParameter(QgsProcessingParameterFeatureSource(
            "INPUT", "Lines or polygons", [QgsProcessing.TypeVectorLine, QgsProcessing.TypeVectorPolygon]))
        self.addParameter(QgsProcessingParameterFeatureSource(
            "POINTS", "Control points (kept on their side)", [QgsProcessing.TypeVectorPoint], optional=True))
        self.addParameter(QgsProcessingParameterEnum(
            "TARGET", "Stop when", options=[label for _, label in cli_args.MAP_TARGETS], defaultValue=0))
        self.addParameter(QgsProcessingParameterNumber(
            "PERCENT", "Share of the vertices to keep (%)", QgsProcessingParameterNumber.Double,
            defaultValue=10.0, minValue=0.0, maxValue=100.0))
        self.addParameter(QgsProcessingParameterNumber(
            "COUNT", "N: vertices to keep or to remove", QgsProcessingParameterNumber.Integer,
            defaultValue=1000, minValue=0, optional=True))
        self.addParameter(QgsProcessingParameterNumber(
            "AREA", "A: effective area (map units squared)", QgsProcessingParameterNumber.Double,
            defaultValue=0.0, minValue=0.0, optional=True))
        self.addParameter(_advanced(QgsProcessingParameterEnum(
            "ARITHMETIC", "Arithmetic", options=[label for _, label in cli_args.ARITHMETIC], defaultValue=0)))
        self.addParameter(QgsProcessingParameterBoolean(
            "VALIDATE", "Validate the result before writing it", defaultValue=False))
        self.addParameter(QgsProcessingParameterNumber(
            "DECIMALS", "Round to D decimals, topology kept", QgsProcessingParameterNumber.Integer,
            minValue=0, maxValue=15, optional=True))
        self.addParameter(_advanced(QgsProcessingParameterNumber(
            "PRECISION", "Round to a grid step (map units), topology kept", QgsProcessingParameterNumber.Double,
            minValue=0.0, optional=True)))
        self.addParameter(_advanced(QgsProcessingParameterNumber(
            "WEIGHTING", "Weighted effective area (0: plain Visvalingam, 0.7: mapshaper's default)",
            QgsProcessingParameterNumber.Double, minValue=0.0, maxValue=1.0, optional=True)))
        self.addParameter(_advanced(QgsProcessingParameterBoolean(
            "SPHERICAL", "Effective areas on the sphere (longitude, latitude layers)", defaultValue=False)))
        self.addParameter(_advanced(QgsProcessingParameterNumber(
            "THREADS", "Threads (0: all cores)", QgsProcessingParameterNumber.Integer,
            defaultValue=0, minValue=0)))
        self.addParameter(QgsProcessingParameterVectorDestination(
            "OUTPUT", "Simplified", QgsProcessing.TypeVectorAnyGeometry))
        self.addOutput(QgsProcessingOutputNumber("VERTICES_IN", "Vertices in"))
        self.addOutput(QgsProcessingOutputNumber("VERTICES_OUT", "Vertices out"))

    def processAlgorithm(self, parameters, context, feedback):
        input_path, input_layer = self.source_file(parameters, "INPUT", context, feedback)
        points_path, points_layer = self.source_file(parameters, "POINTS", context, feedback)
        destination = self.parameterAsOutputLayer(parameters, "OUTPUT", context)
        output_path, output_layer = self.whole_file_destination(destination)
        try:
            args = cli_args.map_args(
                input_path, output_path, input_layer=input_layer, output_layer=output_layer,
                points_path=points_path, points_layer=points_layer,
                target=self.parameterAsEnum(parameters, "TARGET", context),
                percent=self.parameterAsDouble(parameters, "PERCENT", context),
                count=self.optional_int(parameters, "COUNT", context),
                area=self.optional_double(parameters, "AREA", context),
                arithmetic=self.parameterAsEnum(parameters, "ARITHMETIC", context),
                validate=self.parameterAsBool(parameters, "VALIDATE", context),
                threads=self.parameterAsInt(parameters, "THREADS", context),
                decimals=self.optional_int(parameters, "DECIMALS", context),
                precision=self.optional_double(parameters, "PRECISION", context),
                weighting=self.optional_double(parameters, "WEIGHTING", context),
                spherical=self.parameterAsBool(parameters, "SPHERICAL", context))
        except cli_args.ArgumentError as error:
            raise QgsProcessingException(str(error))
        code, summary = self.run_toposimp(args, feedback)
        if code is None:
            return {}
        return {"OUTPUT": destination, "VERTICES_IN": summary.get("vertices_in"),
                "VERTICES_OUT": summary.get("vertices_out")}


class CheckAlgorithm(ToposimpAlgorithm):
    NAME = "check"
    DISPLAY_NAME = "Check a simplification (topology and control points)"
    GROUP = "Maps"
    GROUP_ID = "maps"
    HELP = ("Compares an original layer with a simplified one (made by any tool) and reports what broke: "
            "lost features, vertices that are not a subset, collapsed or flipped rings, invalid polygons, "
            "new or lost crossings and touchings, borders no longer shared, control points now in "
            "another polygon or on the other side of a line. Features are matched by the key field, or "
            "by order.\nThe violations can be written as a point layer to see where they are.")

    def initAlgorithm(self, config=None):
        types = [QgsProcessing.TypeVectorLine, QgsProcessing.TypeVectorPolygon]
        self.addParameter(QgsProcessingParameterFeatureSource("ORIGINAL", "Original", types))
        self.addParameter(QgsProcessingParameterFeatureSource("SIMPLIFIED", "Simplified", types))
        self.addParameter(QgsProcessingParameterFeatureSource(
            "POINTS", "Control points", [QgsProcessing.TypeVectorPoint], optional=True))
        self.addParameter(QgsProcessingParameterField(
            "KEY", "Match features by this field (empty: by order)", parentLayerParameterName="ORIGINAL",
            optional=True))
        self.addParameter(QgsProcessingParameterFileDestination(
            "ERRORS", "Violations (points)", "GeoJSON (*.geojson)", optional=True, createByDefault=False))
        self.addOutput(QgsProcessingOutputBoolean("CLEAN", "Clean"))
        self.addOutput(QgsProcessingOutputNumber("VIOLATIONS", "Violations"))
        self.addOutput(QgsProcessingOutputString("REPORT", "Report (JSON)"))

    def processAlgorithm(self, parameters, context, feedback):
        original, original_layer = self.source_file(parameters, "ORIGINAL", context, feedback)
        simplified, simplified_layer = self.source_file(parameters, "SIMPLIFIED", context, feedback)
        points, points_layer = self.source_file(parameters, "POINTS", context, feedback)
        errors = self.parameterAsFileOutput(parameters, "ERRORS", context) if parameters.get("ERRORS") else None
        try:
            args = cli_args.check_args(original, simplified, layer=original_layer,
                                       simplified_layer=simplified_layer, points_path=points,
                                       points_layer=points_layer,
                                       key_field=self.parameterAsString(parameters, "KEY", context) or None,
                                       errors_path=errors)
        except cli_args.ArgumentError as error:
            raise QgsProcessingException(str(error))
        code, summary = self.run_toposimp(args, feedback)
        if code is None:
            return {}
        violations = len(summary.get("violations", []))
        counts = {kind: n for kind, n in summary.get("counts", {}).items() if n}
        if code == 0:
            feedback.pushInfo("clean: {} features compared".format(summary.get("features")))
        else:
            feedback.reportError("{} violation(s): {}".format(
                violations, ", ".join("{} {}".format(n, kind) for kind, n in sorted(counts.items()))), False)
        results = {"CLEAN": code == 0, "VIOLATIONS": violations, "REPORT": json.dumps(summary)}
        if errors:
            results["ERRORS"] = errors
            context.addLayerToLoadOnCompletion(
                errors, QgsProcessingContext.LayerDetails("toposimp violations", context.project(), "ERRORS"))
        return results


class _MeshTargets:
    """The target parameters of the mesh and DEM algorithms."""

    def add_target_parameters(self, default_percent):
        self.addParameter(QgsProcessingParameterEnum(
            "TARGET", "Stop when", options=[label for _, label in cli_args.MESH_TARGETS], defaultValue=0))
        self.addParameter(QgsProcessingParameterNumber(
            "PERCENT", "Share of the faces to keep (%)", QgsProcessingParameterNumber.Double,
            defaultValue=default_percent, minValue=0.0, maxValue=100.0))
        self.addParameter(QgsProcessingParameterNumber(
            "COUNT", "N: faces to keep", QgsProcessingParameterNumber.Integer, defaultValue=10000, minValue=0,
            optional=True))
        self.addParameter(QgsProcessingParameterNumber(
            "MAX_ERROR", "E: error bound (units; for terrain the vertical distance)", QgsProcessingParameterNumber.Double, defaultValue=1.0,
            minValue=0.0, optional=True))
        self.addParameter(QgsProcessingParameterBoolean(
            "HAUSDORFF", "Measure the Hausdorff distance", defaultValue=True))
        self.addParameter(_advanced(QgsProcessingParameterNumber(
            "THREADS", "Threads (0: all cores)", QgsProcessingParameterNumber.Integer, defaultValue=0, minValue=0)))
        self.addOutput(QgsProcessingOutputNumber("FACES_IN", "Faces in"))
        self.addOutput(QgsProcessingOutputNumber("FACES_OUT", "Faces out"))
        self.addOutput(QgsProcessingOutputNumber("HAUSDORFF_DISTANCE", "Hausdorff distance (units)"))

    def target_values(self, parameters, context):
        return dict(
            target=self.parameterAsEnum(parameters, "TARGET", context),
            percent=self.parameterAsDouble(parameters, "PERCENT", context),
            count=self.optional_int(parameters, "COUNT", context),
            max_error=self.optional_double(parameters, "MAX_ERROR", context),
            hausdorff=self.parameterAsBool(parameters, "HAUSDORFF", context),
            threads=self.parameterAsInt(parameters, "THREADS", context))

    @staticmethod
    def mesh_results(summary):
        return {"FACES_IN": summary.get("faces_in"), "FACES_OUT": summary.get("faces_out"),
                "HAUSDORFF_DISTANCE": summary.get("hausdorff", {}).get("max")}


def _mesh_formats():
    """The mesh formats the toposimp that would run reads and writes ([] if it cannot be found)."""
    try:
        return runner.mesh_formats(runner.find_executable(settings.configured_executable()))
    except runner.ExecutableNotFound:
        return []


class MeshAlgorithm(_MeshTargets, ToposimpAlgorithm):
    NAME = "mesh"
    DISPLAY_NAME = "Simplify a triangle mesh"
    GROUP = "Meshes and terrain"
    GROUP_ID = "meshes"
    HELP = ("Quadric-error edge collapse that never makes the surface touch or cross itself, turn a face "
            "over or lose its manifoldness (exact predicates). Terrain: the faces must keep their "
            "orientation in the map plane (a TIN with z = height). Lock the border to keep tiles "
            "matching. Normals, colours, texture coordinates and other vertex properties are kept (a "
            "merged vertex blends its two ends'). STL corners are welded on reading; weld the vertices "
            "of other unwelded meshes (every face with corners of its own) with the option.")

    def displayName(self):  # noqa: N802
        titles = [f["title"] for f in _mesh_formats()]
        return "{} ({})".format(self.DISPLAY_NAME, ", ".join(titles)) if titles else self.DISPLAY_NAME

    def initAlgorithm(self, config=None):
        inputs, outputs = runner.mesh_file_filters(_mesh_formats())
        self.addParameter(QgsProcessingParameterFile("INPUT", "Mesh", fileFilter=inputs))
        self.add_target_parameters(10.0)
        self.addParameter(QgsProcessingParameterBoolean("TERRAIN", "Terrain (TIN over the x-y plane)", False))
        self.addParameter(QgsProcessingParameterBoolean("LOCK_BOUNDARY", "Keep the border vertices", False))
        self.addParameter(QgsProcessingParameterBoolean(
            "TRIANGULATE", "Split polygons into triangles (else they are an error)", False))
        self.addParameter(QgsProcessingParameterBoolean(
            "WELD", "Merge vertices at the same location first (unwelded meshes)", False))
        self.addParameter(QgsProcessingParameterFileDestination("OUTPUT", "Simplified mesh", outputs))

    def processAlgorithm(self, parameters, context, feedback):
        output = self.parameterAsFileOutput(parameters, "OUTPUT", context)
        try:
            args = cli_args.mesh_args(
                self.parameterAsFile(parameters, "INPUT", context), output,
                terrain=self.parameterAsBool(parameters, "TERRAIN", context),
                lock_boundary=self.parameterAsBool(parameters, "LOCK_BOUNDARY", context),
                triangulate=self.parameterAsBool(parameters, "TRIANGULATE", context),
                weld=self.parameterAsBool(parameters, "WELD", context),
                **self.target_values(parameters, context))
        except cli_args.ArgumentError as error:
            raise QgsProcessingException(str(error))
        code, summary = self.run_toposimp(args, feedback)
        if code is None:
            return {}
        return dict(self.mesh_results(summary), OUTPUT=output)


class DemAlgorithm(_MeshTargets, ToposimpAlgorithm):
    NAME = "dem"
    DISPLAY_NAME = "DEM to simplified TIN"
    GROUP = "Meshes and terrain"
    GROUP_ID = "meshes"
    HELP = ("Triangulates a DEM band over its cell centres (cells without data left out) and simplifies "
            "the TIN with quadric-error edge collapses; no triangle ever folds over in the map plane "
            "(exact orient2d). The border stays as it is unless you free it, so neighbouring tiles "
            "still match. Stopping at an error E keeps the TIN within E of the DEM's surface straight "
            "above or below, everywhere (exact tests; the border is then kept). The result is a layer "
            "of triangles (Polygon Z) in the DEM's CRS.")

    def initAlgorithm(self, config=None):
        self.addParameter(QgsProcessingParameterRasterLayer("INPUT", "DEM"))
        self.addParameter(QgsProcessingParameterBand("BAND", "Band", 1, "INPUT", optional=True))
        self.add_target_parameters(5.0)
        self.addParameter(QgsProcessingParameterBoolean(
            "FREE_BOUNDARY", "Let the border move (tiles will no longer match)", False))
        self.addParameter(QgsProcessingParameterVectorDestination(
            "OUTPUT", "TIN", QgsProcessing.TypeVectorPolygon))

    def processAlgorithm(self, parameters, context, feedback):
        layer = self.parameterAsRasterLayer(parameters, "INPUT", context)
        if layer is None:
            raise QgsProcessingException("no DEM layer")
        if layer.providerType() != "gdal":
            raise QgsProcessingException("the DEM must be a raster GDAL can read (not a '{}' layer)".format(
                layer.providerType()))
        destination = self.parameterAsOutputLayer(parameters, "OUTPUT", context)
        output_path, output_layer = self.whole_file_destination(destination)
        try:
            args = cli_args.mesh_args(
                layer.source(), output_path, band=self.optional_int(parameters, "BAND", context) or 1,
                free_boundary=self.parameterAsBool(parameters, "FREE_BOUNDARY", context),
                output_layer=output_layer, **self.target_values(parameters, context))
        except cli_args.ArgumentError as error:
            raise QgsProcessingException(str(error))
        code, summary = self.run_toposimp(args, feedback)
        if code is None:
            return {}
        return dict(self.mesh_results(summary), OUTPUT=destination)
