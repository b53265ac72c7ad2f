return pge.model()
