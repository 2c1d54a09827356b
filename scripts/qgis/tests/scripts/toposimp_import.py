"""A Processing script for qgis_process_test.py: imports the toposimp Python package inside QGIS's
own Python (as its console would) and simplifies the sample's borders with it."""
from qgis.core import QgsProcessingAlgorithm, QgsProcessingOutputNumber, QgsProcessingOutputString


class ToposimpImport(QgsProcessingAlgorithm):
    """import toposimp, then toposimp.simplify and toposimp.check on the sample's borders."""

    def name(self):
        return "toposimp_import"

    def displayName(self):
        return "toposimp import"

    def createInstance(self):
        return ToposimpImport()

    def initAlgorithm(self, config=None):
        self.addOutput(QgsProcessingOutputString("MODULE", "module"))
        self.addOutput(QgsProcessingOutputNumber("VERTICES_OUT", "vertices out"))

    def processAlgorithm(self, parameters, context, feedback):
        import os
        import geopandas
        import toposimp
        path = os.path.join(os.environ["TOPOSIMP_TESTDATA"], "nh_borders.gpkg")
        borders = geopandas.read_file(path, layer="borders")
        out = toposimp.simplify(borders, keep=0.1)
        assert toposimp.check(borders, out).empty
        return {"MODULE": toposimp.__file__, "VERTICES_OUT": toposimp.summary(out)["vertices_out"]}
